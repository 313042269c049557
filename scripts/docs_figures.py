#!/usr/bin/env python3
"""Checks the hand-written parts of README.md and docs/*.md for the figures that drift (issue 53):
a figure that a generated table holds is not typed again, it names its table.

usage: docs_figures.py [FILE ...]   (default: README.md and docs/*.md; scripts/lint.sh runs it)

What it catches, each against the generated tables of docs/protocol.md (scripts/docs_tables.py):
  - a frame's size typed in prose ("a 191-byte actuator frame", "the sensor frame is 35 bytes") that
    is neither that frame's size nor its payload's in the table protocol_frame;
  - a fault's bit number typed next to its name ("`overflow` (bit 12") or a table of fault bits
    outside docs/protocol.md's protocol_faults;
  - an instruction count in the README ("about 9 600 instructions"): it names
    docs/benchmarks.md's tables instead.
Not checked: the generated blocks themselves (ctest docs_tables_*), and history, a region between
<!-- history: ... --> and <!-- end history --> whose figures are those of their dates.
Exit 1 listing each finding as FILE:LINE: what.
"""
import glob
import os
import re
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
GENERATED = re.compile(r"<!-- generated: (\w+) [^\n]*-->\n(.*?)\n<!-- end: \1 -->", re.S)
HISTORY = re.compile(r"<!-- history:[^\n]*-->\n.*?\n<!-- end history -->", re.S)
FRAME_WORDS = r"(sensor|actuator|command|answer|state|setpoint_velocity|setpoint|trace|param_answer|param|hello)"


def generated(path, name):
    with open(os.path.join(ROOT, path)) as f:
        for m in GENERATED.finditer(f.read()):
            if m.group(1) == name:
                return m.group(2)
    raise SystemExit(f"docs_figures.py: {path} has no generated table '{name}'")


def frame_sizes():
    """{frame type: {its size, its payload's}} from docs/protocol.md's protocol_frame."""
    block = generated("docs/protocol.md", "protocol_frame")
    sizes = {}
    for n, kind in re.findall(r"(\d+) \((\w+)\)", block):  # the payload lengths: 29 (sensor), ...
        sizes.setdefault(kind, set()).add(int(n))
    for kind, n in re.findall(r"\b[Aa]n? (\w+) frame (?:is )?(\d+)", block):  # A sensor frame is 35 bytes, ...
        sizes.setdefault(kind, set()).add(int(n))
    sizes["hello"] = sizes["actuator"]  # the hello frame is an actuator frame
    return sizes


def fault_names():
    return re.findall(r"^\| \d+ \| `0x[0-9A-F]+` \| `(\w+)` \|", generated("docs/protocol.md", "protocol_faults"), re.M)


def blanked(text):
    """The text with its generated and history blocks blanked (line numbers kept)."""
    def blank(m):
        return re.sub(r"[^\n]", " ", m.group(0))
    return HISTORY.sub(blank, GENERATED.sub(blank, text))


def findings(path, text, sizes, faults):
    text = blanked(text)
    flat = text.replace("\n", " ")  # a figure may be split over two lines

    def line(pos):
        return text.count("\n", 0, pos) + 1

    out = []
    number = r"(\d[\d ]*\d|\d)"
    typed = [(m.start(), m.group(2), m.group(1))
             for m in re.finditer(number + r"-byte " + FRAME_WORDS + r" frame", flat)]
    typed += [(m.start(), m.group(1), m.group(2))
              for m in re.finditer(FRAME_WORDS + r" frames? (?:is|are|of) " + number + r" bytes", flat)]
    typed += [(m.start(), m.group(1), m.group(2))  # "one actuator frame (six DAC codes, ...; 191 bytes)"
              for m in re.finditer(FRAME_WORDS + r" frame \([^()]{0,300}?; " + number + r" bytes\)", flat)]
    for pos, kind, n in typed:
        n = int(n.replace(" ", ""))
        if n not in sizes.get(kind, {n}):
            out.append((line(pos), f"the {kind} frame typed as {n} bytes: docs/protocol.md's protocol_frame says "
                        f"{' or '.join(map(str, sorted(sizes[kind])))} (name the table instead)"))
    names = "|".join(map(re.escape, faults))
    for m in re.finditer(r"`(" + names + r")`[^.;]{0,40}?\bbits? \d+|\bbits? \d+[^.;]{0,20}?`(" + names + r")`", flat):
        out.append((line(m.start()), f"fault `{m.group(1) or m.group(2)}` with a bit number: name docs/protocol.md's "
                    "protocol_faults instead"))
    if not path.endswith("docs/protocol.md"):
        last = -2
        for m in re.finditer(r"^\| *\d+ *\| *`(" + names + r")` *\|", text, re.M):
            if line(m.start()) != last + 1:  # once a table
                out.append((line(m.start()), "a table of fault bits: docs/protocol.md's protocol_faults is the one"))
            last = line(m.start())
    if os.path.basename(path) == "README.md":
        for m in re.finditer(number + r" instructions", flat):
            out.append((line(m.start()), f"{m.group(1)} instructions in the README: name docs/benchmarks.md's "
                        "target_instructions (or docs/fixed_point.md's m3_instructions) instead"))
    return out


def main(argv):
    paths = argv[1:] or [os.path.join(ROOT, "README.md")] + sorted(glob.glob(os.path.join(ROOT, "docs", "*.md")))
    sizes, faults = frame_sizes(), fault_names()
    n = 0
    for path in paths:
        with open(path) as f:
            text = f.read()
        for ln, what in sorted(findings(path, text, sizes, faults)):
            print(f"{os.path.relpath(path, ROOT)}:{ln}: {what}")
            n += 1
    if n:
        print(f"docs_figures.py: {n} figure(s) typed in prose that a generated table holds")
    return 1 if n else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
