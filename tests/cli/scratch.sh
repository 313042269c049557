# Sourced by the install tests (python_install.sh, cpp_client_install.sh): a scratch folder $tmp, removed
# on exit with the simulator started into $sim_pid (if any) stopped first, and fail MESSAGE (prints
# FAIL: MESSAGE, exits 1).
tmp=$(mktemp -d)
sim_pid=
cleanup() {
  if [ -n "$sim_pid" ]; then
    kill -TERM "$sim_pid" 2>/dev/null || true
    wait "$sim_pid" 2>/dev/null || true
  fi
  rm -rf "$tmp"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*"
  exit 1
}
