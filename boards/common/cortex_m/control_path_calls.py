#!/usr/bin/env python3
"""Checks that a firmware image's control path calls no forbidden routine.

usage: control_path_calls.py IMAGE.elf ROOT_REGEX FORBIDDEN_REGEX [--objdump PROGRAM]

Builds the static call graph of the image from its disassembly (every direct call and tail call:
bl, b.w and b to another function's symbol) and walks it from every function whose (mangled)
symbol matches ROOT_REGEX, e.g. the control interrupt. Fails (exit 1), printing a call chain,
when a reachable function matches FORBIDDEN_REGEX, e.g. the soft double-precision routines
__aeabi_d*. Prints the number of functions reached otherwise. Calls through function pointers are
not followed (the control path has none: no virtual calls on the interrupt path).
"""
import argparse
import collections
import re
import subprocess
import sys


def call_graph(elf, objdump):
    out = subprocess.run([objdump, "-d", "--no-show-raw-insn", elf], capture_output=True, text=True, check=True).stdout
    graph = collections.defaultdict(set)
    fn = None
    head = re.compile(r"^[0-9a-f]+ <(.+)>:$")
    call = re.compile(r"\s(?:bl|blx|b|b\.w|b\.n|b[a-z]{2}(?:\.w|\.n)?)\s+[0-9a-f]+ <([^>+]+)(\+0x[0-9a-f]+)?>")
    for line in out.splitlines():
        m = head.match(line)
        if m:
            fn = m.group(1)
            graph[fn]
            continue
        m = call.search(line)
        if fn and m and m.group(1) != fn and not m.group(2):
            graph[fn].add(m.group(1))
    return graph


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("elf")
    ap.add_argument("root")
    ap.add_argument("forbidden")
    ap.add_argument("--objdump", default="arm-none-eabi-objdump")
    a = ap.parse_args(argv[1:])
    graph = call_graph(a.elf, a.objdump)
    roots = [f for f in graph if re.search(a.root, f)]
    if not roots:
        print(f"control_path_calls: no function of {a.elf} matches {a.root!r}", file=sys.stderr)
        return 2
    parent = {r: None for r in roots}
    queue = collections.deque(roots)
    bad = []
    while queue:
        f = queue.popleft()
        if re.search(a.forbidden, f):
            bad.append(f)
            continue
        for g in sorted(graph.get(f, ())):
            if g not in parent:
                parent[g] = f
                queue.append(g)
    name = a.elf.rsplit("/", 1)[-1]
    if bad:
        print(f"FAIL: {name}: the control path ({', '.join(roots)}) reaches {len(bad)} forbidden routine(s):")
        for f in bad:
            chain, g = [], f
            while g is not None:
                chain.append(g)
                g = parent[g]
            print("  " + " <- ".join(chain))
        return 1
    print(f"{name}: the control path ({len(parent)} functions reached from {len(roots)} root(s) matching "
          f"{a.root!r}) calls nothing matching {a.forbidden!r}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
