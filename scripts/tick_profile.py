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
       [--top 40] [--depth N] [--lines] [--stage monitors] [--phase 0|1] [--m3-cycles]
--m3-cycles: the tick's cycles on a Cortex-M3 instead, an estimate from the instructions executed and
the branches taken with the TRM's timings at their worst, at zero wait states and from a 72 MHz
STM32F103's flash (m3_estimate).
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
    blocks = {}  # block start -> [(address, size, kind)]
    insns = {}  # address -> (mnemonic, operands, size)
    counts = collections.Counter()
    windows = []  # per handler entry: the instructions until the next entry
    taken = []  # per handler entry: the blocks that ended in a taken branch (a jump, a call, a return)
    fall = None  # where the last block executed in a tick falls through to
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
                    insns[int(m.group(1), 16)] = (m.group(3), m.group(4), size)
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
                taken.append(0)
                inside = True
                stack = []
                fall = None
            if not inside:
                continue
            if fall is not None and pc != fall:
                taken[-1] += 1
            while stack and stack[-1][0] == pc:
                stack.pop()
            block = blocks.get(pc, [(pc, 2, "")])
            sites = tuple(site for _, site in stack)
            w = windows[-1]
            for a, _, _ in block:
                w[(sites, a)] += 1
            a, size, kind = block[-1]
            fall = a + size
            if kind == "call":
                stack.append((a + size, a))
            elif kind == "return" and not stack:
                inside = False  # the handler returned: what follows is main's until the next tick
    # The last two windows hold main's report (the image's last ticks interrupt it).
    kept = [k for k in range(len(windows) - 2) if phase is None or k % 2 == phase]
    for k in kept:
        counts.update(windows[k])
    return counts, len(kept), insns, sum(taken[k] for k in kept)


# Cortex-M3 instruction timings (ARM DDI 0337, Cortex-M3 Technical Reference Manual, "Processor
# instruction timings", zero wait states), each at its worst: a long multiply 5 (3 to 5), a long
# multiply-accumulate 7 (4 to 7), a division 12 (2 to 12), a load or store 2 (a neighbour's pipelining
# not counted), a multiple one 1 + N; a branch 1, and P = 3 (1 to 3) more when taken.
M3_CYCLES = {"smull": 5, "umull": 5, "smlal": 7, "umlal": 7, "sdiv": 12, "udiv": 12, "mla": 2, "mls": 2,
             "ldrd": 3, "strd": 3}
M3_REFILL = 3
M3_EXCEPTION = 12 + 12  # entry and return (the TRM's interrupt latency; a return is as long, at most)
# A 72 MHz STM32F103's flash: 2 wait states (RM0008, 3.3.3), behind a prefetch buffer of two 64-bit
# words. Modelled: a taken branch waits for its line (2 more cycles), and a line of 8 bytes takes 3 cycles.
FLASH_WAIT = 2
FLASH_BYTES_PER_CYCLE = 8 / 3


def m3_cycles(mnemonic, operands):
    """Cycles of one instruction on the Cortex-M3 at zero wait states, a branch as not taken."""
    base = mnemonic.split(".")[0]
    if base in M3_CYCLES:
        return M3_CYCLES[base]
    if base.startswith(("ldm", "stm", "push", "pop")):
        return 1 + len(re.findall(r"\b(r\d+|sb|sl|fp|ip|sp|lr|pc)\b", operands.split("{")[-1]))
    if base.startswith(("ldr", "str")):
        return 2
    return 1


def m3_classes(counts, insns):
    """Per class of instruction (its mnemonic without suffix or condition): instructions and cycles,
    at zero wait states with every branch as not taken."""
    out = collections.defaultdict(lambda: [0, 0])
    for (_, a), k in counts.items():
        if a in insns:
            m, ops, _ = insns[a]
            out[m.split(".")[0]][0] += k
            out[m.split(".")[0]][1] += k * m3_cycles(m, ops)
    return out


def m3_estimate(counts, insns, taken, ticks):
    """The tick's cycles on a Cortex-M3, from its instructions and taken branches: at zero wait
    states, and from a 72 MHz STM32F103's flash (the larger of the core's cycles and the fetches'),
    and per class of instruction (per tick, most cycles first)."""
    classes = m3_classes(counts, insns)
    n = sum(counts.values())
    core = sum(c for _, c in classes.values()) + taken * M3_REFILL + ticks * M3_EXCEPTION
    fetch = sum(k * insns[a][2] for (_, a), k in counts.items() if a in insns) / FLASH_BYTES_PER_CYCLE
    flash = max(core, fetch) + taken * FLASH_WAIT
    per_class = sorted(((key, k / ticks, c / ticks) for key, (k, c) in classes.items()), key=lambda r: -r[2])
    return n / ticks, core / ticks, flash / ticks, per_class


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
    p.add_argument("--m3-cycles", action="store_true",
                   help="estimate the tick's cycles on a Cortex-M3 (the TRM's timings) and from a 72 MHz part's flash")
    p.add_argument("--qemu", default="qemu-system-arm")
    p.add_argument("--nm", default="arm-none-eabi-nm")
    p.add_argument("--addr2line", default="arm-none-eabi-addr2line")
    p.add_argument("--timeout", type=int, default=600)
    args = p.parse_args()
    handler_lo, _ = symbol_range(args.image, args.nm, args.handler)
    with tempfile.TemporaryDirectory() as d:
        log = os.path.join(d, "trace.log")
        output = run_trace(args, log)
        counts, ticks, insns, taken = parse(log, handler_lo & ~1, args.phase)
    if ticks == 0:
        sys.exit(f"tick_profile: no tick seen (the image's output: {output.strip()[-400:]})")
    if args.m3_cycles:
        n, core, flash, per_class = m3_estimate(counts, insns, taken, ticks)
        print(f"{ticks} ticks; per tick: {n:.0f} instructions, {taken / ticks:.0f} taken branches")
        print(f"Cortex-M3 cycles per tick, zero wait states: {core:.0f} (cycles per instruction {core / n:.2f})")
        print(f"Cortex-M3 cycles per tick, 72 MHz flash (2 wait states): {flash:.0f} (cycles per instruction "
              f"{flash / n:.2f}; {flash / 72:.0f} us at 72 MHz)")
        print(f"  taken branches' refills: {taken / ticks * M3_REFILL:.0f} cycles; exception entry and return: "
              f"{M3_EXCEPTION}")
        for key, k, c in per_class[:args.top]:
            print(f"  {key:10s} {k:8.0f} instructions {c:8.0f} cycles")
        return
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
