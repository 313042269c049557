#!/usr/bin/env bash
# The Python client installs offline from Debian's packages alone (README.md, "Python client"): a
# virtual environment over the system's packages (python3-venv; pyserial is python3-serial, setuptools
# and wheel python3-setuptools and python3-wheel), pip without build isolation and without an index.
# Then, from another directory: osc-client --help, a bad verb exits 2, import osc_client finds the
# installed package and its protocol description; given OSC_SIM, osc-client --port PTY state against
# osc_sim --pty prints the state frame (disabled).
#
# usage: python_install.sh PYTHON CLIENT_DIR [OSC_SIM]   (CLIENT_DIR: clients/python)
set -euo pipefail
py=$1 client=$2 sim=${3:-}
# $tmp, its cleanup on exit (stopping $sim_pid), fail.
. "${BASH_SOURCE[0]%/*}/scratch.sh"
# A copy: pip builds in the tree it is given (build/, *.egg-info), and the source tree stays clean.
cp -r "$client" "$tmp/client"
rm -rf "$tmp/client/build" "$tmp/client"/src/*.egg-info
unset PYTHONPATH OSC_PROTOCOL
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1
"$py" -m venv --system-site-packages "$tmp/venv" || fail "$py -m venv (Debian: apt-get install python3-venv)"
"$tmp/venv/bin/pip" install --no-build-isolation --no-index "$tmp/client" >"$tmp/pip.log" 2>&1 ||
  { cat "$tmp/pip.log"; fail "pip install --no-build-isolation --no-index clients/python"; }
tail -1 "$tmp/pip.log"
mkdir "$tmp/elsewhere"
cd "$tmp/elsewhere"
"$tmp/venv/bin/osc-client" --help >"$tmp/help" || fail "osc-client --help exited $?"
grep -q '^usage: osc-client' "$tmp/help" || fail "osc-client --help printed no usage: $(cat "$tmp/help")"
echo "osc-client --help: $(head -1 "$tmp/help")"
rc=0
"$tmp/venv/bin/osc-client" --port /dev/null fly 2>"$tmp/err" || rc=$?
[ "$rc" -eq 2 ] || fail "osc-client --port /dev/null fly exited $rc, expected 2"
where=$("$tmp/venv/bin/python" -c 'import osc_client; print(osc_client.__file__); print(osc_client.Protocol().poses)') ||
  fail "import osc_client"
echo "import osc_client: $where"
case "$where" in
  "$tmp/venv/"*) ;;
  *) fail "osc_client imported from $where, not the virtual environment" ;;
esac
if [ -n "$sim" ]; then
  "$sim" --pty >"$tmp/sim.out" 2>"$tmp/sim.err" &
  sim_pid=$!
  port=
  for _ in $(seq 600); do
    port=$(sed -n '1s/^pty: //p' "$tmp/sim.out")
    [ -n "$port" ] && [ -e "$port" ] && break
    kill -0 "$sim_pid" 2>/dev/null || fail "osc_sim exited: $(cat "$tmp/sim.err")"
    sleep 0.05
  done
  [ -n "$port" ] || fail "osc_sim printed no 'pty: PATH' line within 30 s"
  "$tmp/venv/bin/osc-client" --port "$port" --timeout 30 state >"$tmp/state" || fail "osc-client state exited $?"
  cat "$tmp/state"
  grep -q '^state: disabled$' "$tmp/state" || fail "osc-client state: no 'state: disabled' line"
fi
echo "PASS: python_client_install"
