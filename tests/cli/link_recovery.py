#!/usr/bin/env python3
"""The command link's recovery on the virtual board (osc_sim --pty), issue 53's defects 3, 5 and 6.

usage: link_recovery.py OSC_SIM CLIENT_SRC [--qemu IMAGE]

CLIENT_SRC: the Python client's package source (clients/python/src). Raw bytes on the terminal (the
frames encoded by the package's Protocol, from the firmware's declarations), one check per line, exit
0 when all pass:
  cut_frame_GAP   half a command frame, then GAP s of silence (10 ms, 80 ms, 0.5 s, 2 s), then a
                  clear: the clear is answered (a frame cut short never swallows the next); the cut
                  command is never answered; the state frames count the cut frame (link field)
  resend          a 10 mm relative move sent twice back to back, and again after its answer: one
                  move of 10 mm, one done, the same accepted answer each time
  link_counters   junk and a frame with a bad CRC: counted in the next state frame's link field
  link_silent     (in process, --speed 2) a 2 s move, then the client silent: aborted link_silent
                  after 0.5 s of wall-clock silence, 1000 ticks (+ 20); with --no-link-watch the same
                  move ends done
  inject          osc_sim --inject encoder-garbage:2@1: the state frames show fault and the
                  encoder's fault bit after 1 s, with no command sent after enable
With --qemu IMAGE the controller is the PIL image in QEMU (the same checks but link_silent, which
--qemu does not watch: docs/protocol.md).
"""
import os
import select
import subprocess
import sys
import termios
import time
import tty

sim, client_src = sys.argv[1], sys.argv[2]
qemu = sys.argv[3:5] == ["--qemu", sys.argv[4]] if len(sys.argv) >= 5 else False
image = sys.argv[4] if qemu else None
sys.path.insert(0, os.path.abspath(client_src))
from osc_client import Answer, Command, NameList, Parser, Protocol, State  # noqa: E402 (the package's source)

P = Protocol()
KEEPALIVE = P.encode(State())
failures, passes = [], []


def check(name, ok, detail=""):
    print(f"{'ok  ' if ok else 'FAIL'} {name}{': ' + detail if detail else ''}", flush=True)
    (passes if ok else failures).append(name)


class Board:
    """osc_sim --pty with the options given; its terminal in raw mode; frames parsed as they come."""

    def __init__(self, *opts):
        args = [sim, "--pty", *opts] + (["--qemu", "--elf", image, "--scalar", "float"] if qemu else [])
        self.proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        line = self.proc.stdout.readline()
        if not line.startswith("pty: "):
            raise SystemExit(f"osc_sim did not start: {line!r} {self.proc.stderr.read()}")
        self.fd = os.open(line[5:].strip(), os.O_RDWR | os.O_NOCTTY)
        tty.setraw(self.fd)
        termios.tcflush(self.fd, termios.TCIOFLUSH)
        self.parser = Parser(P)
        self.answers, self.states, self.last_write = [], [], 0.0
        self.next_id = 1000

    def close(self):
        os.close(self.fd)
        self.proc.terminate()
        _, err = self.proc.communicate(timeout=30)
        return err

    def write(self, data):
        os.write(self.fd, data)
        self.last_write = time.monotonic()

    def command(self, verb, position=(0.0, 0.0, 0.0), relative=False, limits=None, cid=None):
        """A command frame's bytes (not sent)."""
        if cid is None:
            self.next_id += 1
            cid = self.next_id
        flags = (P.command_flags["relative"] if relative else 0) | (P.command_flags["has_limits"] if limits else 0)
        return cid, P.encode(Command(id=cid, verb=P.code_of(NameList.VERBS, verb), flags=flags,
                                     position=tuple(position), limits=tuple(limits or ())))

    def pump(self, seconds, keepalive=True, until=None):
        """Reads frames for `seconds` (or until until() holds), a keep-alive every 0.1 s if asked."""
        end = time.monotonic() + seconds
        while time.monotonic() < end and not (until and until()):
            if keepalive and time.monotonic() - self.last_write >= 0.1:
                self.write(KEEPALIVE)
            if select.select([self.fd], [], [], 0.02)[0]:
                for raw in self.parser.feed(os.read(self.fd, 4096)):
                    frame = P.decode(raw.type, raw.payload)
                    if isinstance(frame, Answer):
                        self.answers.append(frame)
                    elif isinstance(frame, State):
                        self.states.append(frame)
        return until() if until else True

    def answered(self, cid):
        return [a for a in self.answers if a.id == cid and a.outcome != 0]

    def state_after(self, seconds=0.2):
        n = len(self.states)
        self.pump(seconds + 1, until=lambda: len(self.states) > n + 1)
        return self.states[-1]

    def link(self, kind):
        """A link error counter of the latest state frame."""
        return self.state_after().link[LINK_KINDS[kind]]


# The link error kinds in their counter order (OSC_LINK_ERROR_LIST).
LINK_KINDS = {k: i for i, k in enumerate(["bad_crc", "bad_header", "bad_length", "junk_bytes", "short_frames",
                                          "seq_errors", "timeouts"])}


def cut_frames(b):
    """Half a command, silence, a clear: the clear answered, the half never."""
    for gap in (0.01, 0.08, 0.5, 2.0):
        short_before = b.link("short_frames")
        crc_before = b.link("bad_crc")
        cut_id, cut = b.command("enable")
        clear_id, clear = b.command("clear")
        b.write(cut[: len(cut) // 2])
        time.sleep(gap)
        b.write(clear)
        ok = b.pump(3, until=lambda: b.answered(clear_id))
        b.pump(0.1)
        counted = b.link("short_frames") - short_before + b.link("bad_crc") - crc_before
        check(f"cut_frame_{gap}", ok and not b.answered(cut_id) and counted == 1,
              f"clear answered {bool(ok)}, the cut enable answered {bool(b.answered(cut_id))}, "
              f"errors counted {counted}")


def resend(b):
    """The same move frame three times: one move of 10 mm, one done."""
    eid, enable = b.command("enable")
    b.write(enable)
    b.pump(3, until=lambda: b.answered(eid))
    z0 = b.state_after().x_d[2]
    mid, move = b.command("move_to", (0.0, 0.0, 0.01), relative=True)
    b.write(move + move)
    b.pump(20, until=lambda: any(a.done_id == mid for a in b.answers))
    b.write(move)
    b.pump(1.0)
    z1 = b.state_after().x_d[2]
    accepted = b.answered(mid)
    done = [a for a in b.answers if a.done_id == mid]
    same = all(a == accepted[0] for a in accepted)
    check("resend", len(done) == 1 and len(accepted) >= 2 and same and abs((z1 - z0) - 0.01) < 5e-4,
          f"moved {1000 * (z1 - z0):.2f} mm, {len(done)} done, {len(accepted)} identical answers: {same}")


def link_counters(b):
    junk_before, crc_before = b.link("junk_bytes"), b.link("bad_crc")
    _, bad = b.command("stop")
    bad = bad[:10] + bytes([bad[10] ^ 0x40]) + bad[11:]
    b.write(bytes([0x11] * 37) + bad)
    b.pump(0.1)
    junk, crc = b.link("junk_bytes") - junk_before, b.link("bad_crc") - crc_before
    check("link_counters", junk >= 37 and crc == 1, f"junk bytes +{junk}, bad CRC +{crc}")


def link_silent(watch):
    b = Board("--speed", "2") if watch else Board("--speed", "2", "--no-link-watch")
    eid, enable = b.command("enable")
    b.write(enable)
    b.pump(3, until=lambda: b.answered(eid))
    mid, move = b.command("move_to", (0.0, 0.0, 0.05), relative=True, limits=[0.025, 0.25, 2.5, 0.5, 1, 10])
    b.write(move)
    b.pump(3, until=lambda: b.answered(mid))
    t0 = b.answers[-1].tick
    b.pump(6, keepalive=False, until=lambda: any(a.aborted_id == mid or a.done_id == mid for a in b.answers))
    end = [a for a in b.answers if a.aborted_id == mid or a.done_id == mid]
    b.close()
    if not end:
        return check(f"link_silent{'' if watch else '_off'}", False, "the move neither aborted nor done")
    a = end[0]
    why = P.name_of(NameList.REASONS, a.abort) if a.aborted_id == mid else "done"
    if watch:
        # 0.5 s of the client's (wall) time: 1000 ticks at --speed 2, and not before 500.
        check("link_silent", why == "link_silent" and 1000 <= a.tick - t0 <= 1020,
              f"{why} {a.tick - t0} ticks after the move's answer")
    else:
        check("link_silent_off", why == "done", f"{why} with --no-link-watch")


def inject():
    b = Board("--inject", "encoder-garbage:2@1")
    eid, enable = b.command("enable")
    b.write(enable)
    b.pump(3, until=lambda: b.answered(eid))
    b.pump(3, until=lambda: b.states and P.name_of(NameList.MOTION_STATES, b.states[-1].state) == "fault")
    s = b.states[-1]
    b.close()
    faults = P.fault_names(s.faults)
    state = P.name_of(NameList.MOTION_STATES, s.state)
    check("inject", state == "fault" and "encoder" in faults, f"state {state}, faults {faults}, tick {s.tick}")


board = Board()
board.pump(0.5)
cut_frames(board)
resend(board)
link_counters(board)
board.close()
if not qemu:
    link_silent(True)
    link_silent(False)
inject()
print(f"{len(passes)} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
