#!/usr/bin/env python3
"""Lists the functions of firmware/, host_sim/, boards/ and tests/boards/ longer than a limit (universal-ctags).

usage: function_lengths.py [--limit N] [--check] [--top K] [PATH ...]

A function's length is its lines from its first to its last (ctags' line and end fields), the
signature and the closing brace included. Default paths: firmware host_sim boards tests/boards (the
boards' test images). --check exits 1 when a function is longer than the limit (default 80); --top K
prints the K longest whatever the limit. Lambdas count within the function that holds them.
"""
import argparse
import os
import subprocess
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
SOURCES = (".cpp", ".hpp", ".h", ".cc")


def functions(paths):
    files = []
    for p in paths:
        p = os.path.join(ROOT, p)
        if os.path.isfile(p):
            files.append(p)
            continue
        for d, _, names in os.walk(p):
            files += [os.path.join(d, n) for n in names if n.endswith(SOURCES)]
    if not files:
        return []
    out = subprocess.run(["ctags", "-f", "-", "--language-force=C++", "--kinds-C++=f", "--fields=+ne", *sorted(files)],
                         capture_output=True, text=True, check=True).stdout
    found = []
    for line in out.splitlines():
        parts = line.split("\t")
        name, path = parts[0], os.path.relpath(parts[1], ROOT)
        fields = dict(f.split(":", 1) for f in parts[3:] if ":" in f)
        if name.startswith("__anon") or "line" not in fields or "end" not in fields:
            continue
        start, end = int(fields["line"]), int(fields["end"])
        scope = next((fields[k] for k in ("class", "struct", "namespace") if k in fields), "")
        found.append((end - start + 1, path, start, (scope + "::" if scope else "") + name))
    return sorted(found, reverse=True)


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--limit", type=int, default=80)
    ap.add_argument("--check", action="store_true", help="exit 1 when a function is longer than the limit")
    ap.add_argument("--top", type=int, default=0, help="print the K longest")
    ap.add_argument("paths", nargs="*", default=["firmware", "host_sim", "boards", "tests/boards"])
    a = ap.parse_args(argv[1:])
    fs = functions(a.paths)
    long = [f for f in fs if f[0] > a.limit]
    for n, path, line, name in (fs[:a.top] if a.top else long):
        print(f"{n:5} {path}:{line} {name}")
    print(f"{len(fs)} functions, {len(long)} longer than {a.limit} lines"
          + (f"; the longest {fs[0][0]} ({fs[0][3]})" if fs else ""))
    return 1 if a.check and long else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
