#!/usr/bin/env python3
"""Writes the Python client's osc_protocol.json from the firmware's declarations (osc_protocol --client).

usage: client_protocol.py [--check] [--host-build DIR]

The Python client (the package osc_client, clients/python/src/osc_client/) builds its frame layouts
and names from that file, its package data, so that nothing of the protocol is typed twice. --check
compares instead of writing and exits 1 when the file differs from what the code declares (ctest
client_protocol_json_current).
"""
import argparse
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "clients", "python", "src", "osc_client", "osc_protocol.json")


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="compare, do not write; exit 1 when stale")
    ap.add_argument("--host-build", default=os.path.join(ROOT, "build", "host"),
                    help="the host preset's build directory")
    a = ap.parse_args(argv[1:])
    exe = os.path.join(a.host_build, "host_sim", "osc_protocol")
    if not os.access(exe, os.X_OK):
        print(f"client_protocol.py: {exe} is not built (cmake --build build/host --target osc_protocol)",
              file=sys.stderr)
        return 2
    new = subprocess.run([exe, "--client"], capture_output=True, text=True, check=True).stdout
    try:
        with open(OUT) as f:
            old = f.read()
    except FileNotFoundError:
        old = None
    if a.check:
        if old == new:
            print(f"current: {os.path.relpath(OUT, ROOT)}")
            return 0
        print(f"STALE: {os.path.relpath(OUT, ROOT)} differs from osc_protocol --client; "
              "regenerate with: python3 scripts/client_protocol.py", file=sys.stderr)
        return 1
    if old != new:
        tmp = OUT + ".tmp"
        with open(tmp, "w") as f:
            f.write(new)
        os.replace(tmp, OUT)
    print(f"{'wrote' if old != new else 'current'}: {os.path.relpath(OUT, ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
