#!/usr/bin/env python3
"""Where a firmware image's 1 kHz tick spends its instructions, from QEMU's execution trace.

Runs IMAGE (a timer image: its tick is the interrupt handler HANDLER, its main function spins
between ticks) in its board's QEMU with `-d in_asm,exec,nochain`, the main function's addresses
filtered out of the log (`-dfilter`), and counts every instruction executed from an entry of the
handler to its return (the calls it makes followed: the stage of an out-of-line function is its
caller's), over every tick but the last two (main's report may hold them). Each instruction's
address is mapped to its source with `addr2line -f -i` (the chain of inlined functions). Prints,
per tick, the instructions of:
  - each tick stage (the outermost `osc::stage_<name>` of the chain),
  - each function (the innermost of the chain, or the K-th level below the stage with --depth),
  - each source line (--lines).

Usage: scripts/tick_profile.py build/m4f/boards/mps2_an386/timer_firmware.elf [--machine mps2-an386]
       [--top 40] [--depth N] [--lines] [--stage monitors] [--phase 0|1]
The counts are of translated blocks' instructions times their executions (an exception that leaves a
block early is not seen: the figure can exceed icount's by a few instructions per tick).
"""
import argparse
import collections
import os
import re
import subprocess
import sys
import tempfile

TRACE = re.compile(r"^Trace \d+: 0x[0-9a-f]+ \[[0-9a-f]+/([0-9a-f]+)/")
STAGE = re.compile(r"\bstage_(\w+)")
INSN = re.compile(r"^0x([0-9a-f]+):\s+((?:[0-9a-f]{4} ?)+)\s+(\S+)\s*(.*)")
RETURN = re.compile(r"^(pop(\.w)?\s.*\bpc\b|bx\s+lr\b|ldm.*\bpc\b)")


def symbol_range(elf, nm, name):
    out = subprocess.run([nm, "-S", "-C", elf], capture_output=True, text=True, check=True).stdout
    for line in out.splitlines():
        f = line.split(maxsplit=3)
        if len(f) == 4 and f[3] == name:
            return int(f[0], 16), int(f[0], 16) + int(f[1], 16)
    sys.exit(f"tick_profile: symbol {name} not found in {elf}")


def run_trace(args, log):
    lo, hi = symbol_range(args.image, args.nm, args.main)
    cmd = [args.qemu, "-M", args.machine, "-display", "none", "-monitor", "none", "-serial", "null",
           "-semihosting-config", "enable=on,target=native", "-icount", "shift=0", "-no-reboot",
           "-kernel", args.image, "-d", "in_asm,exec,nochain", "-dfilter", f"0..0x{lo - 1:x},0x{hi:x}..0xffffffff",
           "-D", log]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
    return r.stdout + r.stderr


def parse(log, handler_pc, phase=None):
    """Per (call sites, address): the instructions executed in the ticks, and the number of ticks.
    The call sites are the out-of-line calls (bl, blx) the instruction is under, from the handler
    down: a call pushes its return address, a block that starts at the top one pops it; a return
    with no call open is the handler's own, which ends the tick's window."""
    blocks = {}  # block start -> [(address, size, is_call)]
    counts = collections.Counter()
    windows = []  # per handler entry: the instructions until the next entry
    inside = False
    current = None
    stack = []  # (return address, call site)
    with open(log, errors="replace") as f:
        for line in f:
            if line.startswith("IN:"):
                current = []
                continue
            if current is not None:
                m = INSN.match(line)
                if m:
                    size = 2 * len(m.group(2).split())
                    kind = "call" if m.group(3) in ("bl", "blx") else "return" if RETURN.match(
                        f"{m.group(3)} {m.group(4)}") else ""
                    current.append((int(m.group(1), 16), size, kind))
                    continue
                if current:
                    blocks[current[0][0]] = current
                current = None
            m = TRACE.match(line)
            if not m:
                continue
            pc = int(m.group(1), 16)
            if pc == handler_pc:
                windows.append(collections.Counter())
                inside = True
                stack = []
            if not inside:
                continue
            while stack and stack[-1][0] == pc:
                stack.pop()
            block = blocks.get(pc, [(pc, 2, "")])
            sites = tuple(site for _, site in stack)
            w = windows[-1]
            for a, _, _ in block:
                w[(sites, a)] += 1
            a, size, kind = block[-1]
            if kind == "call":
                stack.append((a + size, a))
            elif kind == "return" and not stack:
                inside = False  # the handler returned: what follows is main's until the next tick
    # The last two windows hold main's report (the image's last ticks interrupt it).
    kept = [w for k, w in enumerate(windows[:-2]) if phase is None or k % 2 == phase]
    for w in kept:
        counts.update(w)
    return counts, len(kept)


def chains(elf, addr2line, addresses):
    """Each address's chain of (function, file:line), innermost first."""
    text = "\n".join(f"0x{a:x}" for a in addresses) + "\n"
    out = subprocess.run([addr2line, "-e", elf, "-f", "-i", "-C", "-a"], input=text, capture_output=True,
                         text=True, check=True).stdout.splitlines()
    result, cur, i = {}, None, 0
    while i < len(out):
        line = out[i]
        if line.startswith("0x"):
            cur = int(line, 16)
            result[cur] = []
            i += 1
            continue
        func, loc = line, out[i + 1] if i + 1 < len(out) else "??"
        result[cur].append((re.sub(r"\(.*", "", func).replace("osc::", ""), re.sub(r" \(discriminator.*", "", loc)))
        i += 2
    return result


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("image")
    p.add_argument("--machine", default="mps2-an386")
    p.add_argument("--handler", default="TIMER0_Handler")
    p.add_argument("--main", default="main")
    p.add_argument("--top", type=int, default=40)
    p.add_argument("--depth", type=int, default=0, help="the function K levels below the stage (0: the innermost)")
    p.add_argument("--stage", help="only this stage's instructions")
    p.add_argument("--lines", action="store_true", help="rank source lines instead of functions")
    p.add_argument("--phase", type=int, choices=(0, 1),
                   help="only every other tick, from the first (0) or the second (1): the tick's two turns apart")
    p.add_argument("--qemu", default="qemu-system-arm")
    p.add_argument("--nm", default="arm-none-eabi-nm")
    p.add_argument("--addr2line", default="arm-none-eabi-addr2line")
    p.add_argument("--timeout", type=int, default=600)
    args = p.parse_args()
    handler_lo, _ = symbol_range(args.image, args.nm, args.handler)
    with tempfile.TemporaryDirectory() as d:
        log = os.path.join(d, "trace.log")
        output = run_trace(args, log)
        counts, ticks = parse(log, handler_lo & ~1, args.phase)
    if ticks == 0:
        sys.exit(f"tick_profile: no tick seen (the image's output: {output.strip()[-400:]})")
    addresses = sorted({a for sites, a in counts} | {c for sites, _ in counts for c in sites})
    ch = chains(args.image, args.addr2line, addresses)
    stages, funcs = collections.Counter(), collections.Counter()
    for (sites, a), n in counts.items():
        # The whole chain, outermost first: each call site's inlined functions, then the instruction's.
        chain = [c for site in sites for c in reversed(ch.get(site, [("??", "??")]))]
        chain += list(reversed(ch.get(a, [("??", "??")])))
        names = [c[0] for c in chain]
        outer = [k for k, name in enumerate(names) if STAGE.search(name)]
        stage = STAGE.search(names[outer[0]]).group(1) if outer else "(outside the stages)"
        if args.stage and stage != args.stage:
            continue
        stages[stage] += n
        if args.lines:
            key = f"{chain[-1][1]} ({names[-1]})"
        elif args.depth and outer:
            key = names[min(outer[0] + args.depth, len(names) - 1)]
        else:
            key = names[-1]
        funcs[key] += n
    total = sum(stages.values())
    print(f"{ticks} ticks; instructions per tick, from the trace: {total / ticks:.0f}")
    for s, n in sorted(stages.items(), key=lambda kv: -kv[1]):
        print(f"  stage {s:24s} {n / ticks:8.0f}")
    print("lines:" if args.lines else "functions:")
    for key, n in funcs.most_common(args.top):
        print(f"  {n / ticks:8.0f}  {key}")


if __name__ == "__main__":
    main()
