#!/usr/bin/env python3
"""A client of the link protocol written from docs/protocol.md alone (Python's struct, no project code).

usage: protocol_client.py PEER PROTOCOL_MD

PEER is a program that speaks the protocol on its standard input and output (pil_peer: the
firmware's link node and control task built for the host). The check:
  1. the layout this client uses (below, typed from the document) is the one the document's
     tables give, field by field;
  2. the document's worked examples decode to what their captions say, and their CRCs check;
  3. a live session with PEER: the hello frame, 50 frames in lockstep with torque, a frame with a
     bad CRC answered at once with zero codes and counted, torque again, then an encoder jump that
     latches its fault with zero torque, and the fault stays;
  4. a second session: an amplifier's fault line in the drive byte (the document's mask) latches
     drive_fault with zero torque in the same tick.
Prints one line per check; exit 0 when all pass, 1 otherwise.
"""
import os
import re
import struct
import subprocess
import sys
import time

# The frame, as docs/protocol.md gives it.
SYNC = b"\xA5\x5A"
SENSOR, ACTUATOR = 1, 2
SENSOR_LAYOUT = [("seq", "u32", 1), ("counts", "i32", 6), ("currents", "i16", 6), ("drive", "u8", 1),
                 ("inject", "u8", 1)]
ACTUATOR_LAYOUT = [("seq", "u32", 1), ("codes", "i32", 6), ("faults", "u32", 1), ("state", "u8", 1),
                   ("step_cycles", "u32", 1), ("max_cycles", "u32", 1), ("mean_cycles", "u32", 1),
                   ("tick_max_cycles", "u32", 1), ("stage_cycles", "u32", 8), ("stack_used", "u32", 1),
                   ("theta_hat", "f32", 18), ("tau_f_hat", "f32", 6), ("link", "u32", 7), ("rx_gap_max", "u32", 1),
                   ("rx_long_gaps", "u32", 1)]
CODE = {"u8": "B", "i16": "h", "u32": "I", "i32": "i", "f32": "f"}


def fmt_of(layout):
    return "<" + "".join(f"{n}{CODE[t]}" for _, t, n in layout)


SENSOR_FMT, ACTUATOR_FMT = fmt_of(SENSOR_LAYOUT), fmt_of(ACTUATOR_LAYOUT)
HELLO_SEQ = 0xFFFFFFFF


def crc16(data):
    """CRC-16/CCITT-FALSE: polynomial 0x1021, initial 0xFFFF, MSB first, no final XOR."""
    crc = 0xFFFF
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else (crc << 1)
            crc &= 0xFFFF
    return crc


def frame(ftype, payload):
    body = bytes([ftype, len(payload)]) + payload
    return SYNC + body + struct.pack("<H", crc16(body))


def sensor(seq, counts, inject=0, currents=(0,) * 6, drive=0):
    return frame(SENSOR, struct.pack(SENSOR_FMT, seq, *counts, *currents, drive, inject))


def decode(layout, payload):
    v, out = struct.unpack(fmt_of(layout), payload), {}
    for name, _, n in layout:
        out[name], v = (v[0] if n == 1 else list(v[:n])), v[n:]
    return out


def decode_actuator(payload):
    return decode(ACTUATOR_LAYOUT, payload)


class Parser:
    """Hunts for A5 5A, then type, length, payload and CRC; drops a bad frame and hunts again."""

    LENGTHS = {SENSOR: struct.calcsize(SENSOR_FMT), ACTUATOR: struct.calcsize(ACTUATOR_FMT)}

    def __init__(self):
        self.buf = b""

    def feed(self, data):
        self.buf += data
        frames = []
        while True:
            i = self.buf.find(SYNC)
            if i < 0:
                self.buf = self.buf[-1:] if self.buf.endswith(b"\xA5") else b""
                return frames
            self.buf = self.buf[i:]
            if len(self.buf) < 4:
                return frames
            ftype, n = self.buf[2], self.buf[3]
            if self.LENGTHS.get(ftype) != n:
                self.buf = self.buf[1:]
                continue
            if len(self.buf) < 6 + n:
                return frames
            body, crc = self.buf[2:4 + n], struct.unpack("<H", self.buf[4 + n:6 + n])[0]
            if crc16(body) == crc:
                frames.append((ftype, body[2:]))
                self.buf = self.buf[6 + n:]
            else:
                self.buf = self.buf[1:]


class Failures:
    def __init__(self):
        self.n = 0

    def check(self, ok, what):
        print(("pass " if ok else "FAIL ") + what)
        self.n += 0 if ok else 1
        return ok


def doc_tables(text):
    """The document's field tables: {heading: [(offset, type, count, name)]}."""
    out = {}
    for heading in ("Sensor frame", "Actuator frame"):
        sec = text[text.index("## " + heading):]
        rows = []
        for line in sec.split("\n"):
            m = re.match(r"\| (\d+) \| (u8|i16|u32|i32|f32)(?: × (\d+))? \| \d+ \| `(\w+)` \|", line)
            if m:
                rows.append((int(m.group(1)), m.group(2), int(m.group(3) or 1), m.group(4)))
            elif rows and not line.startswith("|"):
                break
        out[heading] = rows
    return out


def drive_bits(text):
    """The drive byte's masks as the document's table gives them: {name: mask}."""
    sec = text[text.index("### The drive byte"):]
    sec = sec[:sec.find("\n#", 1)]  # to the next heading
    return {m.group(2): int(m.group(1), 16) for m in re.finditer(r"\| [\d-]+ \| `0x([0-9A-F]{2})` \| (\w+) \|", sec)}


def layout_rows(layout):
    """(offset, type, count, name) of each field of a layout."""
    rows, off = [], 0
    for name, t, n in layout:
        rows.append((off, t, n, name))
        off += n * struct.calcsize("<" + CODE[t])
    return rows


def check_document(text, f):
    t = doc_tables(text)
    f.check(t["Sensor frame"] == layout_rows(SENSOR_LAYOUT),
            f"the sensor payload this client sends is the document's table ({len(t['Sensor frame'])} fields)")
    f.check(t["Actuator frame"] == layout_rows(ACTUATOR_LAYOUT),
            f"the actuator payload this client reads is the document's table ({len(t['Actuator frame'])} fields)")
    f.check(f"`0x{crc16(b'123456789'):04X}`" in text, "the CRC's check value 123456789 is the document's")
    ex = re.findall(r"\n([^\n]*?) \((\d+) bytes\):\n\n```\n(.*?)```", text[text.index("## Worked examples"):], re.S)
    f.check(len(ex) == 3, f"three worked examples ({len(ex)})")
    for caption, n, dump in ex:
        data = bytes(int(h, 16) for line in dump.strip().split("\n") for h in line.split()[1:])
        frames = Parser().feed(data)
        if not f.check(len(data) == int(n) and len(frames) == 1, f"example '{caption[:40]}...' is one valid frame"):
            continue
        ftype, payload = frames[0]
        if ftype == SENSOR:
            s_ = decode(SENSOR_LAYOUT, payload)
            seq, counts, inject = s_["seq"], tuple(s_["counts"]), s_["inject"]
            words = [int(x) for x in re.findall(r"-?\d+", caption.split("counts")[-1])] if "counts" in caption else []
            ok = f"sequence {seq}" in caption or f"frame {seq}" in caption
            ok = ok and (counts == tuple(words[:6]) if words else counts == (0,) * 6)
            if "paper" in caption:  # the adaptation law + 1 in bits 5-6: paper is law 0
                ok = ok and inject == (0 + 1) << 5
            drive = drive_bits(text)
            if "currents " in caption:  # the readings, the valid bit, the fault line named
                words = [int(x) for x in re.findall(r"-?\d+", caption.split("currents ")[1])]
                line = re.search(r"amplifier (\d+)'s fault line", caption)
                ok = ok and tuple(s_["currents"]) == tuple(words[:6])
                lines = 1 << (int(line.group(1)) - 1) if line else 0
                ok = ok and s_["drive"] == drive["currents_valid"] | lines
            else:
                ok = ok and tuple(s_["currents"]) == (0,) * 6 and s_["drive"] == 0
            f.check(ok, f"example sensor frame {seq} decodes to its caption")
        else:
            a = decode_actuator(payload)
            ok = (f"frame {a['seq']}" in caption and "codes 120, -9100, 2047, 0, -15, 3" in caption
                  and a["codes"] == [120, -9100, 2047, 0, -15, 3] and a["state"] == 1 and a["faults"] == 0
                  and a["theta_hat"][0] == 1.5 and a["tau_f_hat"][0] == -0.25 and a["link"][5] == 1
                  and a["rx_gap_max"] == 250000 and a["step_cycles"] == 9560 and a["stack_used"] == 2960)
            f.check(ok, f"example actuator frame {a['seq']} decodes to its caption")


class Peer:
    def __init__(self, argv):
        env = dict(os.environ, OSC_PIL_PEER_TIMEOUT_MS="10000")  # no silence while this machine is busy
        self.p = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, env=env)
        self.parser = Parser()
        self.pending = []

    def send(self, data):
        self.p.stdin.write(data)
        self.p.stdin.flush()

    def receive(self, timeout=10.0):
        end = time.monotonic() + timeout
        while not self.pending:
            if time.monotonic() > end:
                raise TimeoutError("no actuator frame")
            data = os.read(self.p.stdout.fileno(), 4096)
            if not data:
                raise EOFError("the peer closed the link")
            self.pending += [decode_actuator(p) for t, p in self.parser.feed(data) if t == ACTUATOR]
        return self.pending.pop(0)

    def close(self):
        self.p.stdin.close()
        self.p.wait(timeout=10)


def check_session(argv, fault_bits, f):
    peer = Peer(argv)
    try:
        hello = peer.receive()
        f.check(hello["seq"] == HELLO_SEQ and hello["codes"] == [0] * 6, "the hello frame: seq 0xFFFFFFFF, zero codes")
        answers = []
        for n in range(50):
            peer.send(sensor(n, [0] * 6))
            answers.append(peer.receive())
        f.check([a["seq"] for a in answers] == list(range(50)), "50 frames in lockstep, each answered with its seq")
        f.check(all(a["state"] == 1 and a["faults"] == 0 for a in answers), "state run, no fault")
        f.check(all(any(a["codes"]) for a in answers), "torque in every answer (the arm held against gravity)")
        bad = bytearray(sensor(50, [0] * 6))
        bad[10] ^= 0x40  # one payload bit
        peer.send(bytes(bad))
        a = peer.receive()
        f.check(a["seq"] == 50 and a["codes"] == [0] * 6 and a["link"][0] == 1 and a["faults"] == 0,
                "a bad CRC: answered at once as frame 50 with zero codes, bad_crc counted, no fault")
        for n in range(51, 55):
            peer.send(sensor(n, [0] * 6))
            a = peer.receive()
        f.check(a["seq"] == 54 and any(a["codes"]) and a["state"] == 1, "torque again after the error")
        peer.send(sensor(55, [5000, 0, 0, 0, 0, 0]))  # joint 1 half a radian in one tick
        a = peer.receive()
        jump = fault_bits["encoder_jump"]
        f.check(a["faults"] & jump and a["state"] == 2 and a["codes"] == [0] * 6,
                "an encoder jump: the encoder_jump bit of the document, state fault, zero codes in the same tick")
        peer.send(sensor(56, [5000, 0, 0, 0, 0, 0]))
        a = peer.receive()
        f.check(a["faults"] & jump and a["codes"] == [0] * 6, "the fault stays latched")
    finally:
        peer.close()


def check_fault_line(argv, text, fault_bits, f):
    """An amplifier's fault line (the document's drive byte) is a drive fault in the tick it comes."""
    lines = drive_bits(text).get("fault_lines", 0)
    f.check(lines == 0x3F, f"the document's drive byte: six fault lines in bits 0-5 (mask {lines:#x})")
    peer = Peer(argv)
    try:
        peer.receive()  # hello
        for n in range(5):
            peer.send(sensor(n, [0] * 6))
            a = peer.receive()
        f.check(a["faults"] == 0 and any(a["codes"]), "no fault line, no current reading: torque, no fault")
        peer.send(sensor(5, [0] * 6, drive=lines & (1 << 1)))  # amplifier 2 trips
        a = peer.receive()
        drive = fault_bits["drive_fault"]
        f.check(a["seq"] == 5 and a["faults"] & drive and a["state"] == 2 and a["codes"] == [0] * 6,
                "amplifier 2's fault line: the document's drive_fault bit, state fault, zero codes in the same tick")
    finally:
        peer.close()


def main(argv):
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    with open(argv[2]) as fh:
        text = fh.read()
    f = Failures()
    check_document(text, f)
    faults = {m.group(2): int(m.group(1), 16) for m in re.finditer(r"\| \d+ \| `0x([0-9A-F]{8})` \| `(\w+)` \|", text)}
    f.check("encoder_jump" in faults, "the document names the encoder_jump bit")
    check_session([argv[1]], faults, f)
    f.check("drive_fault" in faults, "the document names the drive_fault bit")
    check_fault_line([argv[1]], text, faults, f)
    print(f"{f.n} failed" if f.n else "all checks passed")
    return 1 if f.n else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
