#!/usr/bin/env python3
"""A client of the controller's command protocol (docs/protocol.md; docs/motion.md, "Clients").

Pure Python 3 with pyserial (Debian's python3-serial). The frame layouts and the names of every code
are not typed here: they come from osc_protocol.json beside this file, which the firmware's own
declarations write (osc_protocol --client; scripts/client_protocol.py; ctest
client_protocol_json_current fails when it is stale). That file is the default arm's (the PUMA 560):
the limits, named poses and parameter ranges are an arm's. For a board built for another arm, give
its build's file (BUILD/clients/osc_protocol.json, which every host build writes) with --protocol
FILE or the environment variable OSC_PROTOCOL.

As a module:

    from osc_client import Client
    c = Client("/dev/pts/7")
    c.wait_answer(c.enable())
    print(c.wait_done(c.move_to((0, 0.02, 0), relative=True)).text())   # done, aborted: stop_command, ...

As a program, the verbs of oscctl, printing the same lines and exiting with the same status (0
accepted or done, 1 refused, aborted or timed out, 2 a bad command line, port or file):

    python3 clients/python/osc_client.py --port /dev/pts/7 state | enable | disable | clear | paper | stop | home
    python3 clients/python/osc_client.py --port /dev/pts/7 declare_pose start | zero | ready | stretch
    python3 clients/python/osc_client.py --port /dev/pts/7 move X Y Z [--rpy R P Y] [--relative]
                                         [--v V --a A --j J] [--replace] [--no-wait]
    python3 clients/python/osc_client.py --port /dev/pts/7 stream FILE.csv --rate HZ [--velocity] [--relative]
    python3 clients/python/osc_client.py --port /dev/pts/7 watch [--seconds S]

A board whose encoders are local (the STM32F4 board) stops a running motion (category 2, aborted
link_silent) when no frame comes from the host for 0.5 s (params::kCommandLinkTimeout): while it
waits, the client sends a keep-alive frame (a state frame, which a controller takes as link activity
and otherwise ignores) whenever it has sent nothing for --keepalive SECONDS (default 0.1, as oscctl;
0: none).
"""
import argparse
import json
import math
import os
import random
import select
import struct
import sys
import time

PROTOCOL_JSON = os.path.join(os.path.dirname(os.path.abspath(__file__)), "osc_protocol.json")


def protocol_path():
    """The protocol's description: $OSC_PROTOCOL when set (a build for another arm), else the default arm's."""
    return os.environ.get("OSC_PROTOCOL") or PROTOCOL_JSON


WIRE = {"u8": "B", "i16": "h", "u32": "I", "i32": "i", "f32": "f"}


class ClientError(Exception):
    """A named error: a bad port, a transport that failed, a bad request or file."""


class Protocol:
    """The command protocol as osc_protocol.json declares it: frame types, layouts, flags, names."""

    def __init__(self, path=None):
        path = protocol_path() if path is None else path
        if not path:
            raise ClientError("the protocol's description: an empty path (--protocol FILE)")
        try:
            with open(path) as f:
                p = json.load(f)
        except (OSError, ValueError) as e:
            raise ClientError(f"{path}: cannot read the protocol's description: {e}")
        self.sync = bytes(p["sync"])
        self.crc_poly, self.crc_init = p["crc"]["poly"], p["crc"]["init"]
        self.control_hz = p["control_hz"]
        self.code = {t["name"]: t["code"] for t in p["types"]}
        self.name = {t["code"]: t["name"] for t in p["types"]}
        self.payload = {t["code"]: t["payload"] for t in p["types"]}
        self.fields = p["fields"]
        self.format = {}
        for name, fields in self.fields.items():
            self.format[name] = "<" + "".join(f"{f['count']}{WIRE[f['type']]}" for f in fields)
            if struct.calcsize(self.format[name]) != self.payload[self.code[name]]:
                raise ClientError(f"{path}: the {name} frame's fields do not add up to its payload")
        self.command_flag = {n: 1 << i for i, n in enumerate(p["command_flags"])}
        self.setpoint_flag = {n: 1 << i for i, n in enumerate(p["setpoint_flags"])}
        self.stream_max_period = p["stream_max_period"]
        self.limits = p["limits"]
        self.faults = p["faults"]
        self.poses = p["poses"]
        self.names = {k: p[k] for k in ("verbs", "motion_states", "reasons", "outcomes", "stop_categories",
                                        "completions")}
        # The parameter table of the firmware's build (osc/runtime/parameters.hpp), its operations,
        # statuses and answer flags.
        self.params = p["parameters"]
        self.param_index = {q["name"]: q["index"] for q in self.params["table"]}
        self.names.update({"param_ops": self.params["ops"], "param_statuses": self.params["statuses"]})
        self.param_flag = {n: 1 << i for i, n in enumerate(self.params["flags"])}

    def code_of(self, kind, name):
        return self.names[kind].index(name)

    def name_of(self, kind, code):
        names = self.names[kind]
        return names[code] if 0 <= code < len(names) else "?"

    def crc16(self, data):
        crc = self.crc_init
        for b in data:
            crc ^= b << 8
            for _ in range(8):
                crc = ((crc << 1) ^ self.crc_poly) if crc & 0x8000 else (crc << 1)
                crc &= 0xFFFF
        return crc

    def encode(self, frame, values):
        """A frame of type `frame` from a dict of its fields (missing ones 0)."""
        flat = []
        for f in self.fields[frame]:
            v = values.get(f["name"], 0)
            flat += list(v) if f["count"] > 1 else [v]
            if f["count"] > 1 and len(v) != f["count"]:
                raise ClientError(f"{frame}.{f['name']}: {f['count']} values, not {len(v)}")
        payload = struct.pack(self.format[frame], *flat)
        body = bytes([self.code[frame], len(payload)]) + payload
        return self.sync + body + struct.pack("<H", self.crc16(body))

    def decode(self, frame, payload):
        v, out = struct.unpack(self.format[frame], payload), {}
        for f in self.fields[frame]:
            n = f["count"]
            out[f["name"]], v = (v[0] if n == 1 else list(v[:n])), v[n:]
        return out

    def fault_names(self, bits):
        if bits == 0:
            return "none"
        return ",".join(self.faults[i] if i < len(self.faults) else f"bit{i}" for i in range(32) if bits >> i & 1)


class Parser:
    """Hunts for the sync pair, then type, length, payload and CRC. A frame that fails (an unknown type,
    a wrong length, a bad CRC, or cut short: expire()) gives up its sync pair and the bytes after it are
    scanned again, so a good frame among them is found (docs/protocol.md, "Framing and
    resynchronisation")."""

    FRAME_TIMEOUT = 0.02  # seconds: the in-frame timeout (params::kFrameTimeout)

    def __init__(self, protocol):
        self.p, self.buf = protocol, b""

    def expire(self):
        """The in-frame timeout: a frame begun is cut short; the frames in the bytes after its start."""
        if not self.buf.startswith(self.p.sync[:1]):
            return []
        self.buf = self.buf[1:]
        return self.feed(b"")

    def feed(self, data):
        """The complete, valid frames in the bytes so far, as (type name, payload)."""
        self.buf += data
        out = []
        while True:
            i = self.buf.find(self.p.sync)
            if i < 0:
                self.buf = self.buf[-1:] if self.buf[-1:] == self.p.sync[:1] else b""
                return out
            self.buf = self.buf[i:]
            if len(self.buf) < 4:
                return out
            ftype, n = self.buf[2], self.buf[3]
            if self.p.payload.get(ftype) != n:
                self.buf = self.buf[2:]  # an unknown type or a wrong length: hunt again after the pair
                continue
            if len(self.buf) < 6 + n:
                return out
            body, crc = self.buf[2:4 + n], struct.unpack("<H", self.buf[4 + n:6 + n])[0]
            if self.p.crc16(body) == crc:
                out.append((self.p.name[ftype], body[2:]))
                self.buf = self.buf[6 + n:]
            else:
                self.buf = self.buf[2:]


class Outcome:
    """What became of a command: status accepted, done, refused, aborted, timeout or error."""

    def __init__(self, status, cid=0, reason="none", cause=0, error="", answer=None, protocol=None):
        self.status, self.id, self.reason, self.cause, self.error = status, cid, reason, cause, error
        self.answer, self._p = answer, protocol
        self.skipped = 0  # a stream's setpoints not sent: the client fell behind its schedule (Client.stream)

    def ok(self):
        return self.status in ("accepted", "done")

    def text(self):
        s = self.status
        if s in ("refused", "aborted"):
            s += f": {self.reason}"
        if self.status == "refused" and self.reason == "faulted":
            s += f" ({self._p.fault_names(self.cause)})"
        if s == "error":
            s += f": {self.error}"
        return s


def read_stream_csv(path):
    """Rows (t, x, y, z, roll, pitch, yaw) in s, m, rad and whether the path has the orientation: the
    CSV that puma_experiment's scripts and oscctl read (t, x, y, z[, roll, pitch, yaw] in s, m,
    degrees; a header row and # comments skipped; t from 0, increasing)."""
    try:
        with open(path) as f:
            lines = f.read().splitlines()
    except OSError:
        raise ClientError(f"{path}: cannot be read")
    rows, columns = [], 0
    for n, line in enumerate(lines, 1):
        where = f"{path}:{n}: "
        s = line.strip(" \t\r")
        if not s or s.startswith("#"):
            continue
        try:
            v = [float(c) for c in s.split(",")]
        except ValueError:
            if not rows and columns == 0:
                columns = -1  # the header
                continue
            raise ClientError(where + "not a row of numbers")
        if len(v) not in (4, 7):
            raise ClientError(where + f"{len(v)} columns: t, x, y, z[, roll, pitch, yaw] needs 4 or 7")
        if columns > 0 and len(v) != columns:
            raise ClientError(where + f"every row needs the same columns ({columns})")
        columns = len(v)
        if not all(math.isfinite(x) for x in v):
            raise ClientError(where + "not a finite number")
        r = v[:4] + [math.radians(x) for x in v[4:]] + [0.0] * (7 - len(v))
        if not rows and r[0] != 0:
            raise ClientError(where + "the path's time starts at 0")
        if rows and not r[0] > rows[-1][0]:
            raise ClientError(where + "t must increase from row to row")
        rows.append(r)
    if not rows:
        raise ClientError(f"{path}: no rows (t, x, y, z[, roll, pitch, yaw])")
    return rows, columns == 7


def angular_velocity(rpy, rpy_rate):
    """The base angular velocity w = E(rpy) rpy_dot of R = Rz(yaw) Ry(pitch) Rx(roll)
    (osc::phi_rate_to_angular)."""
    sb, cb, sg, cg = math.sin(rpy[1]), math.cos(rpy[1]), math.sin(rpy[2]), math.cos(rpy[2])
    r = rpy_rate
    return [cg * cb * r[0] - sg * r[1], sg * cb * r[0] + cg * r[1], -sb * r[0] + r[2]]


def resample_path(rows, rate_hz):
    """The path sampled every 1 / rate_hz s from t = 0, linearly between rows, with its velocity
    there (the segment's slope: linear, then angular in the base frame; zero at the end); the last
    sample is the path's end. A list of (position, rpy, velocity) (osc::client::resample_path)."""
    out, T, end, i, n = [], 1.0 / rate_hz, rows[-1][0], 1, 0
    while True:
        t = n * T
        last = t >= end - 1e-9
        while i < len(rows) and rows[i][0] < t:
            i += 1
        x, v = rows[-1], [0.0] * 6
        if not last:
            a, b = rows[i - 1], rows[i]
            dt = b[0] - a[0]
            f = (t - a[0]) / dt
            x = [a[c] + f * (b[c] - a[c]) for c in range(7)]
            rate = [(b[c] - a[c]) / dt for c in range(1, 7)]
            v = rate[:3] + angular_velocity(x[4:7], rate[3:])
        out.append((x[1:4], x[4:7], v))
        if last:
            return out
        n += 1


class Client:
    """The command protocol over a serial device or pseudo-terminal (raw mode, any baud rate)."""

    HISTORY = 1024
    RESEND = 0.5  # seconds without an answer before a command is sent again
    SENT_KEPT = 64

    KEEPALIVE = 0.1  # seconds, as oscctl's default

    def __init__(self, port, baud=115200, protocol=None, keepalive=KEEPALIVE):
        self.p = protocol or Protocol()
        self.keepalive, self._last_write = keepalive, time.monotonic()
        try:
            import serial
        except ImportError:
            raise ClientError("pyserial is missing (Debian: apt-get install python3-serial)")
        self._serial_error = serial.SerialException
        try:
            fd = os.open(port, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        except OSError as e:
            raise ClientError(f"{port}: {e.strerror}")
        tty = os.isatty(fd)
        os.close(fd)
        if not tty:
            raise ClientError(f"{port}: not a serial device or terminal")
        try:
            self.ser = serial.Serial(port, baud, timeout=0)
            self.ser.reset_input_buffer()  # an earlier client's unread bytes
        except (serial.SerialException, ValueError, OSError) as e:
            raise ClientError(f"{port}: {e}")
        self.port = port
        self.parser = Parser(self.p)
        self.next_id = random.randint(1, 2**30)  # unique across clients: no earlier client's answers
        self.answers, self.latest_state, self.states_seen = [], None, 0
        self.param_answer = None
        self.on_answer = self.on_state = None
        self._sent = {}  # the frames of the last SENT_KEPT commands, by id (resent unchanged)

    def close(self):
        self.ser.close()

    # ------------------------------------------------------------------ commands: each returns its id
    def command(self, verb, position=(0.0, 0.0, 0.0), rpy=None, relative=False, replace=False, limits=None,
                period=0):
        """One command frame. rpy [rad] or None; limits: six numbers (linear v, a, j, angular v, a, j) or None."""
        cid = self.next_id
        self.next_id = self.next_id % 0xFFFFFFFF + 1
        flags = ((self.p.command_flag["relative"] if relative else 0) | (self.p.command_flag["has_rpy"] if rpy else 0)
                 | (self.p.command_flag["replace"] if replace else 0)
                 | (self.p.command_flag["has_limits"] if limits else 0))
        frame = self.p.encode("command", {
            "id": cid, "verb": self.p.code_of("verbs", verb), "flags": flags, "position": list(position),
            "rpy": list(rpy or (0.0, 0.0, 0.0)), "limits": list(limits or [0.0] * 6), "period": period})
        self._sent[cid] = frame
        if len(self._sent) > self.SENT_KEPT:
            del self._sent[next(iter(self._sent))]
        self._write(frame)
        return cid

    def enable(self):
        return self.command("enable")

    def disable(self):
        return self.command("disable")

    def stop(self):
        return self.command("stop")

    def clear(self):
        return self.command("clear")

    def paper(self):
        return self.command("paper")

    def home(self):
        """Homing: each motor to its index pulse from the pots' coarse angles; wait_done for its end."""
        return self.command("home")

    def declare_pose(self, pose):
        """The arm stands at the named pose (osc_protocol.json's poses; torque off): its code in period."""
        if pose not in self.p.poses:
            raise ClientError(f"'{pose}' is not a named pose: {', '.join(self.p.poses)}")
        return self.command("declare_pose", period=self.p.poses.index(pose))

    def move_to(self, position, rpy=None, relative=False, replace=False, limits=None):
        return self.command("move_to", position, rpy, relative, replace, limits)

    def limits(self, v=None, a=None, j=None):
        """Six limits: the linear ones given, the others the configured maxima (None when none given)."""
        if v is None and a is None and j is None:
            return None
        lin = self.p.limits["linear"]
        return [v or lin[0], a or lin[1], j or lin[2]] + list(self.p.limits["angular"])

    def stream(self, points, has_rpy, rate_hz, relative=False, limits=None, answer_timeout=10, velocity=False):
        """The stream command, its answer awaited, then one setpoint per period paced by the wall clock,
        the last with the end flag; points: (position, rpy) or (position, rpy, velocity) each (with
        velocity=True, setpoint_velocity frames: no delay of one period). The stream command's answer
        once every setpoint is sent (accepted: wait_done(outcome.id) for its end), or its refusal, an
        abort while sending, a timeout."""
        period = 1000.0 / rate_hz
        if abs(period - round(period)) > 1e-9 or not 1 <= round(period) <= self.p.stream_max_period:
            raise ClientError(f"rate {rate_hz:g} Hz: 1000 / N Hz for a whole N from 1 to "
                              f"{self.p.stream_max_period} (1000, 500, 250, 100, 50, 20, 10 ...)")
        if not points:
            raise ClientError("a stream needs at least one setpoint")
        cid = self.command("stream", relative=relative, limits=limits, period=int(round(period)))
        o = self.wait_answer(cid, answer_timeout)
        if o.status != "accepted":
            return o
        t0, T = time.monotonic(), 1.0 / rate_hz
        for n, point in enumerate(points):
            last = n + 1 == len(points)
            # Behind the schedule (its successor is due already): skipped rather than sent in a burst,
            # which the board would only overwrite (it keeps the newest setpoint not yet taken).
            if not last and time.monotonic() >= t0 + (n + 1) * T:
                o.skipped += 1
                continue
            if self._read_until(t0 + n * T, lambda: self._evaluate(cid, True).status in ("done", "aborted")):
                e = self._evaluate(cid, True)
                e.skipped = o.skipped
                return e
            pos, rpy = point[0], point[1]
            flags = (self.p.setpoint_flag["end"] if last else 0) | (self.p.setpoint_flag["has_rpy"] if has_rpy else 0)
            values = {"id": cid, "flags": flags, "position": list(pos), "rpy": list(rpy) if has_rpy else [0.0] * 3}
            if velocity:
                values["velocity"] = list(point[2])
            self._write(self.p.encode("setpoint_velocity" if velocity else "setpoint", values))
        return o

    # ------------------------------------------------------------------ answers and state
    def param(self, op, index=0, element=0, value=0.0, timeout=5.0):
        """A parameter request (get, set, save, load, reset, check): its param_answer frame (a dict). A
        timeout, or an answer from a firmware with another parameter table, raises ClientError."""
        cid = self.next_id
        self.next_id = self.next_id % 0xFFFFFFFF + 1
        self._write(self.p.encode("param", {"id": cid, "op": self.p.code_of("param_ops", op), "index": index,
                                            "element": element, "value": value}))
        self.param_answer = None
        if not self._read_until(time.monotonic() + timeout,
                                lambda: self.param_answer is not None and self.param_answer["id"] == cid):
            raise ClientError(f"param {op}: no answer within {timeout:g} s")
        a = self.param_answer
        table = self.p.params
        if a["layout"] != table["layout"] or a["count"] != len(table["table"]):
            raise ClientError(f"param: the controller's parameter table (layout {a['layout']}, {a['count']} "
                              f"parameters) is not this client's (layout {table['layout']}, {len(table['table'])}): "
                              "use the client of its build")
        return a

    def state(self, timeout=5.0):
        """The latest state frame (a dict), received after this call; None on a timeout."""
        seen = self.states_seen
        return self.latest_state if self._read_until(time.monotonic() + timeout, lambda: self.states_seen > seen) \
            else None

    def wait_answer(self, cid, timeout=10.0):
        """accepted or refused (or timeout). Without an answer the command is sent again, the same frame,
        every RESEND seconds: the board runs it once and answers a repeat with the answer it gave."""
        box = [None]

        def decided():
            box[0] = self._evaluate(cid, False)
            return box[0].status != "timeout"
        self._read_until(time.monotonic() + timeout, decided, resend=cid)
        return box[0]

    def wait_done(self, cid, timeout=120.0):
        """A motion done at rest or aborted (the reason); a stop or disable done at rest; any other
        command done once accepted; refused (the reason); or timeout."""
        box = [None]

        def decided():
            box[0] = self._evaluate(cid, True)
            return box[0].status not in ("timeout", "accepted")
        self._read_until(time.monotonic() + timeout, decided, resend=cid)
        if box[0].status == "accepted":
            box[0].status = "timeout"
        return box[0]

    def pump(self, timeout):
        """Reads and dispatches frames (on_answer, on_state) for timeout seconds."""
        self._read_until(time.monotonic() + timeout, lambda: False)

    # ------------------------------------------------------------------ inside
    def _write(self, data):
        try:
            self.ser.write(data)
        except (self._serial_error, OSError) as e:
            raise ClientError(f"{self.port}: {e}")
        self._last_write = time.monotonic()

    def _keep_alive(self):
        """A state frame (all zero) when nothing was sent for self.keepalive seconds: link activity for a
        board that stops a motion when its command link goes silent."""
        if self.keepalive and time.monotonic() - self._last_write >= self.keepalive:
            self._write(self.p.encode("state", {f["name"]: [0] * f["count"] if f["count"] > 1 else 0
                                                for f in self.p.fields["state"]}))

    def _read_until(self, deadline, done, resend=None):
        """Reads frames until done() or the deadline. resend: a command's id, whose frame is sent again
        every RESEND seconds while it has no answer (a client's recovery rule: docs/protocol.md)."""
        last_rx = sent = time.monotonic()
        while not done():
            now = time.monotonic()
            left = deadline - now
            if left <= 0:
                return False
            if resend in self._sent and now - sent >= self.RESEND:
                if self._evaluate(resend, False).status == "timeout":  # no answer yet
                    self._write(self._sent[resend])
                sent = now
            self._keep_alive()
            try:
                ready = select.select([self.ser.fileno()], [], [], min(left, 0.05))[0]
                data = self.ser.read(4096) if ready else b""
            except (self._serial_error, OSError):
                raise ClientError(f"{self.port}: hung up (the board or the simulator has gone)")
            if data:
                last_rx = time.monotonic()
                frames = self.parser.feed(data)
            elif time.monotonic() - last_rx >= Parser.FRAME_TIMEOUT:
                frames = self.parser.expire()
            else:
                frames = []
            for frame, payload in frames:
                self._dispatch(frame, payload)
        return True

    def _dispatch(self, frame, payload):
        if frame == "param_answer":
            self.param_answer = self.p.decode("param_answer", payload)
        elif frame == "answer":
            a = self.p.decode("answer", payload)
            self.answers = (self.answers + [a])[-self.HISTORY:]
            if self.on_answer:
                self.on_answer(a)
        elif frame == "state":
            self.latest_state = self.p.decode("state", payload)
            self.states_seen += 1
            if self.on_state:
                self.on_state(self.latest_state)

    def _evaluate(self, cid, until_done):
        """The command's answer and end as far as the answers so far tell (timeout: not yet)."""
        name = self.p.name_of
        motion_verbs = {self.p.code_of("verbs", v) for v in ("move_to", "paper", "stream", "home")}
        accepted = wait_rest = motion = False
        o = Outcome("timeout", cid, protocol=self.p)
        for a in self.answers:
            if not accepted:
                if a["id"] != cid or name("outcomes", a["outcome"]) == "none":
                    continue
                o.answer = a
                if name("outcomes", a["outcome"]) == "refused":
                    o.status, o.reason, o.cause = "refused", name("reasons", a["refusal"]), a["cause"]
                    return o
                accepted, o.status = True, "accepted"
                if not until_done:
                    return o
                motion = a["verb"] in motion_verbs
                wait_rest = not motion and name("motion_states", a["state"]) == "stopping"
                if not motion and not wait_rest:
                    o.status = "done"
                    return o
                continue
            if wait_rest and name("completions", a["completion"]) != "none" or motion and a["done_id"] == cid:
                o.answer, o.status = a, "done"
                return o
            # A motion ends in exactly one answer naming it: done, or aborted with a reason (a move still
            # queued when the motion ahead of it was stopped, re-targeted or faulted: dropped).
            if motion and a["aborted_id"] == cid and name("reasons", a["abort"]) != "none":
                o.answer, o.status, o.reason = a, "aborted", name("reasons", a["abort"])
                return o
        return o

    # ------------------------------------------------------------------ text, as oscctl prints it
    def state_text(self, s):
        n = self.p.name_of

        def pose(x):
            d = [math.degrees(v) for v in x[3:]]
            return f"{x[0]:.4f} {x[1]:.4f} {x[2]:.4f} m, rpy {d[0]:.2f} {d[1]:.2f} {d[2]:.2f} deg"
        return (f"state: {n('motion_states', s['state'])}\nstop: {n('stop_categories', s['stop'])}\n"
                f"faults: {self.p.fault_names(s['faults'])}\nqueued: {s['queued']}\nrunning_id: {s['running_id']}\n"
                f"reference: {pose(s['x_d'])}\nmeasured: {pose(s['x'])}\ndropped: {s['dropped']}\n"
                f"tick: {s['tick']}\n")

    def answer_text(self, a):
        n = self.p.name_of
        t = f"tick {a['tick']}:"
        if n("outcomes", a["outcome"]) != "none":
            t += f" {n('verbs', a['verb'])} {a['id']} {n('outcomes', a['outcome'])}"
            if n("outcomes", a["outcome"]) == "refused":
                t += f": {n('reasons', a['refusal'])}"
            if a["cause"]:
                t += f" ({self.p.fault_names(a['cause'])})"
            t += ";"
        if a["done_id"]:
            t += f" done {a['done_id']};"
        if n("reasons", a["abort"]) != "none":
            t += f" aborted {a['aborted_id']}: {n('reasons', a['abort'])};"
        if n("completions", a["completion"]) != "none":
            t += f" completion {n('completions', a['completion'])};"
        return t + f" state {n('motion_states', a['state'])}, queued {a['queued']}"


# ---------------------------------------------------------------------- the command line (oscctl's verbs)
def report(o):
    print(o.text(), flush=True)
    return 0 if o.ok() else 2 if o.status == "error" else 1


def cmd_simple(c, a):
    cid = c.command(a.verb)
    o = c.wait_answer(cid, a.timeout)
    rc = report(o)
    if o.status != "accepted":
        return rc
    if c.p.name_of("reasons", o.answer["abort"]) != "none":
        print(f"aborted {o.answer['aborted_id']}: {c.p.name_of('reasons', o.answer['abort'])}", flush=True)
    if a.verb not in ("stop", "disable", "home"):
        return rc
    return report(c.wait_done(cid, a.timeout))


def cmd_declare_pose(c, a):
    return report(c.wait_answer(c.declare_pose(a.pose), a.timeout))


def cmd_move(c, a):
    cid = c.move_to(a.xyz, [math.radians(x) for x in a.rpy] if a.rpy else None, a.relative, a.replace,
                    c.limits(a.v, a.a, a.j))
    o = c.wait_answer(cid, a.timeout)
    print(f"{o.text()} (id {cid})", flush=True)
    if o.status != "accepted" or a.no_wait:
        return 0 if o.ok() else 1
    return report(c.wait_done(cid, a.timeout))


def cmd_stream(c, a):
    rows, has_rpy = read_stream_csv(a.file)
    o = c.stream(resample_path(rows, a.rate), has_rpy, a.rate, a.relative, c.limits(a.v, a.a, a.j), a.timeout,
                 a.velocity)
    print(f"{o.text()} (id {o.id})", flush=True)
    if o.skipped:
        print(f"osc_client: warning: {o.skipped} setpoints skipped: this client fell behind the stream's schedule",
              file=sys.stderr)
    if o.status != "accepted":
        return 0 if o.ok() else 1
    return report(c.wait_done(o.id, a.timeout))


def cmd_state(c, a):
    s = c.state(min(a.timeout, 10.0))
    if s is None:
        print("osc_client: no state frame within the time (is a controller on the port?)", file=sys.stderr)
        return 1
    print(c.state_text(s), end="")
    return 0


def cmd_watch(c, a):
    last = {}

    def on_state(s):
        keys = ("state", "stop", "faults", "queued", "running_id")
        if last and all(s[k] == last[k] for k in keys):
            return
        n = c.p.name_of
        print(f"tick {s['tick']}: state {n('motion_states', s['state'])}, stop {n('stop_categories', s['stop'])}, "
              f"faults {c.p.fault_names(s['faults'])}, queued {s['queued']}, running_id {s['running_id']}", flush=True)
        last.update(s)
    c.on_answer = lambda f: print(c.answer_text(f), flush=True)
    c.on_state = on_state
    try:
        c.pump(a.seconds if a.seconds else float("inf"))
    except KeyboardInterrupt:
        pass
    return 0


def param_line(c, q, a):
    """One element's line, as oscctl prints it: "ks[2] = 97 (0.001 to 100000; torque_off)"."""
    idx = f"[{a['element']}]" if q["count"] > 1 else ""
    unit = f" {q['unit']}" if q["unit"] else ""
    off = "; torque_off" if a["flags"] & c.p.param_flag["torque_off"] else ""
    return f"{q['name']}{idx} = {a['value']:.7g}{unit} ({a['lo']:.7g} to {a['hi']:.7g}{off})"


def param_refused(c, a):
    """0 when ok, else 1 with the reason printed."""
    if a["status"] == 0:
        return 0
    print(f"refused: {c.p.name_of('param_statuses', a['status'])}")
    return 1


def margins_text(c, a):
    warn = ": warning, the paper's sufficient condition cannot hold" \
        if a["flags"] & c.p.param_flag["warn_37"] else ""
    return (f"observer margin {a['margins'][0]:.3g} (stable above 1: (4 - 2 k dt) / (b dt^2), b <= "
            f"{a['margins'][1]:.4g} 1/s^2 at the last pose)\n"
            f"loop margin {a['margins'][3]:.3g} (stable at 1 or above: the factor the gains may grow by "
            f"at the last pose)\n"
            f"condition (37) {a['margins'][2]:.3g} (k_s k_nd / 2: above 1 it can hold){warn}")


def check_param(ap, p, a):
    """The param command line's own checks, as oscctl's: a known name, as many values as elements."""
    if a.op not in ("get", "set"):
        if a.name is not None or a.values:
            ap.error(f"param {a.op} takes no name")
        return
    if a.name not in p.param_index:
        ap.error(f"param {a.name}: no such parameter ({', '.join(q['name'] for q in p.params['table'])})")
    n = p.params["table"][p.param_index[a.name]]["count"]
    if a.element is not None and not 0 <= a.element < n:
        ap.error(f"param {a.name} --element {a.element}: it has {n} element" + ("s" if n > 1 else ""))
    if a.op == "get":
        if a.values:
            ap.error("param get takes no value")
        return
    want = 1 if a.element is not None else n
    if len(a.values) != want:
        ap.error(f"param set {a.name}: {want} value" + ("s" if want > 1 else "") + (
            " (one element)" if a.element is not None else " (one per element; --element E sets one)") +
            f", got {len(a.values)}")


def cmd_param(c, a):
    t = c.p.params["table"]
    if a.op == "list":
        for q in t:
            for e in range(q["count"]):
                r = c.param("get", q["index"], e, timeout=a.timeout)
                if param_refused(c, r):
                    return 1
                print(param_line(c, q, r))
        return 0
    if a.op in ("get", "set"):
        q = t[c.p.param_index[a.name]]
        if a.op == "get":
            for e in range(q["count"]):
                if a.element is None or e == a.element:
                    r = c.param("get", q["index"], e, timeout=a.timeout)
                    if param_refused(c, r):
                        return 1
                    print(param_line(c, q, r))
            return 0
        for k, v in enumerate(a.values):
            e = a.element if a.element is not None else k
            r = c.param("set", q["index"], e, v, timeout=a.timeout)
            if param_refused(c, r):
                if r["margins"][1] > 0:
                    print(margins_text(c, r))
                return 1
            print(param_line(c, q, r))
            if r["flags"] & c.p.param_flag["warn_37"]:
                print(margins_text(c, r))
        return 0
    r = c.param(a.op, timeout=a.timeout)
    if param_refused(c, r):
        return 1
    print(margins_text(c, r) if a.op == "check" else f"{a.op}: ok")
    return 0


def positive(text):
    v = float(text)
    if not v > 0:
        raise argparse.ArgumentTypeError(f"{text}: must be above 0")
    return v


def keepalive_seconds(text):
    v = float(text)
    if not 0 <= v <= 0.4:
        raise argparse.ArgumentTypeError(f"{text}: must be from 0 (none) to 0.4 (below the board's 0.5 s timeout)")
    return v


def parser():
    ap = argparse.ArgumentParser(prog="osc_client.py", description=__doc__.split("\n")[0] + " Exit status 0: "
                                 "accepted or done; 1: refused, aborted or timed out; 2: a bad command line, port "
                                 "or file.")
    ap.add_argument("--port", required=True, help="the serial device or pseudo-terminal (e.g. /dev/pts/7)")
    ap.add_argument("--baud", type=int, default=115200, help="baud rate of a serial device (default 115200)")
    ap.add_argument("--protocol", metavar="FILE", help="the board's osc_protocol.json (default: $OSC_PROTOCOL, else "
                    "the default arm's beside this file); a build for another arm writes BUILD/clients/"
                    "osc_protocol.json")
    ap.add_argument("--timeout", type=positive, default=120.0, help="seconds to wait for an answer or an end")
    ap.add_argument("--keepalive", type=keepalive_seconds, default=Client.KEEPALIVE,
                    help="while waiting, a keep-alive frame after this many seconds without a frame sent (default "
                         "0.1; 0: none): a board with local encoders stops a motion after 0.5 s of link silence")
    sub = ap.add_subparsers(dest="verb", required=True, metavar="VERB")
    for v in ("state", "enable", "disable", "clear", "paper", "stop", "home"):
        sub.add_parser(v, help="print the state frame" if v == "state" else f"send {v}")
    dp = sub.add_parser("declare_pose", help="the arm stands at a named pose (torque off; the pots must agree)")
    dp.add_argument("pose", help="the pose's name (osc_protocol.json's poses: start, zero, ready, stretch)")

    def limits(p):
        p.add_argument("--v", type=positive, help="linear speed limit [m/s]")
        p.add_argument("--a", type=positive, help="linear acceleration limit [m/s^2]")
        p.add_argument("--j", type=positive, help="linear jerk limit [m/s^3]")
        p.add_argument("--relative", action="store_true", help="offsets from where the queue ends (or the stream "
                       "starts)")
    m = sub.add_parser("move", help="a jerk-limited move_to of the wrist centre; waits until done")
    m.add_argument("xyz", type=float, nargs=3, metavar="X/Y/Z", help="X Y Z [m], base frame")
    m.add_argument("--rpy", type=float, nargs=3, metavar=("R", "P", "Y"), help="roll pitch yaw [deg]")
    m.add_argument("--replace", action="store_true", help="re-target the running motion instead of queueing")
    m.add_argument("--no-wait", action="store_true", help="return once accepted")
    limits(m)
    s = sub.add_parser("stream", help="stream a CSV path (t, x, y, z[, roll, pitch, yaw] in s, m, deg)")
    s.add_argument("file")
    s.add_argument("--rate", type=positive, required=True, help="setpoints per second: 1000 / N, N from 1 to 100")
    s.add_argument("--velocity", action="store_true",
                   help="send each setpoint with the path's velocity (its slope between rows): no delay of one period")
    limits(s)
    w = sub.add_parser("watch", help="print state changes and every answer")
    w.add_argument("--seconds", type=positive, help="for this long (default: until interrupted)")
    pm = sub.add_parser("param", help="the controller's parameters: list, get, set, save, load, reset, check")
    pm.add_argument("op", choices=["list", "get", "set", "save", "load", "reset", "check"])
    pm.add_argument("name", nargs="?", help="the parameter (get, set)")
    pm.add_argument("values", type=float, nargs="*", help="set: one value per element, or one with --element")
    pm.add_argument("--element", type=int, help="get, set: only this element of a vector parameter")
    return ap


def main(argv):
    ap = parser()
    # A bad command line: argparse's message, exit status 2. param's values may follow its options
    # (set k --element 0 2500): numbers left over after a param are its values.
    a, extra = ap.parse_known_args(argv)
    if extra and a.verb == "param":
        try:
            a.values += [float(x) for x in extra]
            extra = []
        except ValueError:
            pass
    if extra:
        ap.error("unrecognized arguments: " + " ".join(extra))
    if a.verb == "move" and not all(math.isfinite(x) for x in a.xyz + (a.rpy or [])):
        ap.error("move: X Y Z and --rpy must be finite numbers")
    if not 50 <= a.baud <= 4000000:
        ap.error(f"--baud {a.baud}: 50 to 4000000")
    try:
        if a.verb == "stream":
            read_stream_csv(a.file)  # a bad file before the port is touched
        protocol = Protocol(a.protocol)
        if a.verb == "param":
            check_param(ap, protocol, a)
        c = Client(a.port, a.baud, protocol=protocol, keepalive=a.keepalive)
        verbs = {"state": cmd_state, "move": cmd_move, "stream": cmd_stream, "watch": cmd_watch, "param": cmd_param,
                 "declare_pose": cmd_declare_pose}
        return verbs.get(a.verb, cmd_simple)(c, a)
    except ClientError as e:
        print(f"osc_client: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
