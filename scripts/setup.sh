#!/usr/bin/env bash
# Installs the Debian packages the project needs; quick and silent when all are present.
set -euo pipefail
pkgs=(cmake ninja-build g++ libeigen3-dev libgtest-dev libbenchmark-dev liborocos-kdl-dev
      gcc-arm-none-eabi libnewlib-arm-none-eabi libstdc++-arm-none-eabi-newlib binutils-arm-none-eabi
      qemu-system-arm python3 python3-matplotlib
      python3-serial                        # the Python client of the command protocol (clients/python/),
      python3-venv python3-pip python3-setuptools python3-wheel   # its offline install (README.md),
      python3-pytest mypy                   # its unit tests and types (ctest python_client_*)
      gdb-multiarch openocd                 # debugging the images (debug_<image>, the QEMU debug test),
                                            # flashing the STM32F4 board (the flash target)
      clang libclang-rt-14-dev llvm-14      # the fuzz preset: clang 14 (Debian 12), its sanitizer and
                                            # libFuzzer runtimes, llvm-symbolizer for the reports
      libyaml-cpp-dev libcli11-dev nlohmann-json3-dev   # the experiment's configuration file, command
                                                        # line and JSON (host tools only)
      liburdfdom-dev                        # the arm generator reads an arm's URDF (tools/armgen)
      clang-format clang-tidy flake8 universal-ctags)   # scripts/lint.sh: style, naming, Python,
                                                        # function lengths
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
