"""Scripted boards: a transport whose controller answers each command as a test says, and one that sends
state frames; a board's capture in memory (FakeCapture) for the first."""
from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from typing import Callable, Iterator

from osc_client import Answer, Capture, CaptureData, Command, Frame, NameList, Param, Parser, Protocol, State

Reply = Callable[[Command], list[Frame]]
ParamReply = Callable[[Param], list[Frame]]
CaptureReply = Callable[[Capture], list[Frame]]


@dataclass
class FakeBoard:
    """Answers each command frame the client writes through ``reply`` (the client reads the frames
    it returns next), each param frame through ``param_reply`` and each capture frame through
    ``capture_reply`` (none: no answer), sends what ``on_read`` returns at each read (a clock's state
    frames), and keeps every frame the client sent."""

    protocol: Protocol
    reply: Reply
    sent: list[Frame] = field(default_factory=list)
    pending: bytes = b""
    param_reply: ParamReply | None = None
    capture_reply: CaptureReply | None = None
    on_read: Callable[[], list[Frame]] | None = None

    def __post_init__(self) -> None:
        self.parser = Parser(self.protocol)

    def read(self, timeout: float) -> bytes:
        if self.on_read is not None:
            time.sleep(min(timeout, 0.002))
            self.pending += b"".join(self.protocol.encode(f) for f in self.on_read())
        data, self.pending = self.pending, b""
        if not data:
            time.sleep(min(timeout, 0.002))
        return data

    def write(self, data: bytes) -> None:
        for raw in self.parser.feed(data):
            frame = self.protocol.decode(raw.type, raw.payload)
            self.sent.append(frame)
            if isinstance(frame, Command):
                self.pending += b"".join(self.protocol.encode(f) for f in self.reply(frame))
            elif isinstance(frame, Param) and self.param_reply is not None:
                self.pending += b"".join(self.protocol.encode(f) for f in self.param_reply(frame))
            elif isinstance(frame, Capture) and self.capture_reply is not None:
                self.pending += b"".join(self.protocol.encode(f) for f in self.capture_reply(frame))

    def close(self) -> None:
        pass

    def commands(self) -> list[Command]:
        """The command frames the client sent, resends included."""
        return [f for f in self.sent if isinstance(f, Command)]

    def captures(self) -> list[Capture]:
        """The capture frames the client sent."""
        return [f for f in self.sent if isinstance(f, Capture)]


def ramp(tick: int, channel: int) -> float:
    """FakeCapture's value of a channel at a tick: the tick, plus a quarter per channel (exact in f32)."""
    return tick + 0.25 * channel


@dataclass
class FakeCapture:
    """A board's capture (osc/link/capture.hpp) in memory, on a clock of its own: ``tick`` goes on by
    ``ticks_per_read`` at each read of the board (``clock``, FakeBoard's on_read, which sends a state frame of
    the tick each time), and the requests (``__call__``, FakeBoard's capture_reply) are answered as the
    firmware answers them. Channel c's value at tick t is ``ramp(t, c)``.

    An armed capture samples each ``divider`` ticks from the tick after the arm; the fault trigger's event is
    tick ``fault_tick`` (None: none comes), a trigger request's the tick after it; the trigger's sample is the
    first at or after the event. ``refuse_arm``: the status that refuses every arm.
    """

    protocol: Protocol
    tick: int = 1000
    ticks_per_read: int = 20
    fault_tick: int | None = 5000
    refuse_arm: str | None = None
    state: str = "idle"
    channels: int = 0
    signal: tuple[int, ...] = ()
    element: tuple[int, ...] = ()
    trigger: int = 0
    divider: int = 1
    pre: int = 0
    armed_tick: int = 0
    event_tick: int | None = None
    reads: int = 0

    def clock(self) -> list[Frame]:
        """A read of the board: the clock on, a state frame of the tick."""
        self.tick += self.ticks_per_read
        return [State(tick=self.tick)]

    def name(self, kind: NameList, code: int) -> str:
        return self.protocol.name_of(kind, code)

    def depth(self) -> int:
        return self.protocol.capture.depth(self.channels)

    def sample_tick(self, k: int) -> int:
        """Sample k's tick (k = 0: the tick after the arm)."""
        return self.armed_tick + 1 + k * self.divider

    def trigger_sample(self) -> int | None:
        """The trigger's sample's index, once its event came (None before)."""
        event = self.event_tick
        if event is None and self.name(NameList.CAPTURE_TRIGGERS, self.trigger) == "fault":
            event = self.fault_tick
        if event is None or event > self.tick:
            return None
        return max(0, -(-(event - self.sample_tick(0)) // self.divider))

    def held(self) -> tuple[int, int, int]:
        """A triggered capture's (pre samples held, the trigger's sample, samples held)."""
        k = self.trigger_sample()
        assert k is not None
        held_pre = min(k, self.pre)
        return held_pre, k, held_pre + 1 + (self.depth() - self.pre - 1)

    def update(self) -> None:
        """Where the capture is at the tick."""
        if self.state not in ("armed", "triggered"):
            return
        k = self.trigger_sample()
        if k is None or self.sample_tick(k) > self.tick:
            return
        self.state = "triggered"
        held_pre, k, held = self.held()
        if self.sample_tick(k + held - held_pre - 1) <= self.tick:
            self.state = "done"

    def __call__(self, f: Capture) -> list[Frame]:
        p = self.protocol
        self.update()
        op = self.name(NameList.CAPTURE_OPS, f.op)
        status = "ok"
        values: tuple[float, ...] = ()
        if op == "arm":
            if self.refuse_arm:
                status, self.state, self.channels = self.refuse_arm, "idle", 0
            else:
                self.state, self.channels, self.signal, self.element = "armed", f.channels, f.signal, f.element
                self.trigger, self.divider, self.pre = f.trigger, f.divider, f.pre
                self.armed_tick, self.event_tick = self.tick, None
        elif op == "trigger":
            if self.state == "armed":
                self.event_tick = self.tick + 1
            else:
                status = "not_armed"
        elif op == "abort":
            self.state, self.channels = "idle", 0
        elif op == "read":
            self.reads += 1
            if self.state != "done":
                status = "not_done"
            else:
                held_pre, k, held = self.held()
                total = held * self.channels
                if f.offset > total:
                    status = "bad_offset"
                first = self.sample_tick(k - held_pre)
                values = tuple(ramp(first + (v // self.channels) * self.divider, v % self.channels)
                               for v in range(f.offset, min(total, f.offset + p.capture.chunk)))
        answer = CaptureData(id=f.id, op=f.op, status=p.code_of(NameList.CAPTURE_STATUSES, status),
                             state=p.code_of(NameList.CAPTURE_STATES, self.state), channels=self.channels,
                             signal=self.signal, element=self.element, trigger=self.trigger, divider=self.divider,
                             pre=self.pre, offset=f.offset if op == "read" else 0, count=len(values),
                             values=values + (0.0,) * (p.capture.chunk - len(values)))
        if self.state in ("triggered", "done"):
            held_pre, k, held = self.held()
            trigger_tick = self.sample_tick(k)
            answer = dataclasses.replace(answer, pre=held_pre, trigger_tick=trigger_tick,
                                         first_tick=trigger_tick - held_pre * self.divider,
                                         depth=held if self.state == "done" else 0)
        return [answer]


def answer(p: Protocol, command: Command, outcome: str = "accepted", refusal: str = "none",
           state: str = "holding", **fields: int) -> Answer:
    """The answer to a command (its id and verb) with the named outcome, refusal and motion state."""
    return Answer(id=command.id, verb=command.verb, outcome=p.code_of(NameList.OUTCOMES, outcome),
                  refusal=p.code_of(NameList.REASONS, refusal), state=p.code_of(NameList.MOTION_STATES, state),
                  **fields)


@dataclass
class StateFeed:
    """A board that sends state frames: the next of ``frames`` at each read (after ``period`` seconds, its
    pace), silence once they are over; it keeps every frame the client wrote (its keep-alives)."""

    protocol: Protocol
    frames: Iterator[State]
    period: float = 0.0
    sent: list[Frame] = field(default_factory=list)
    closed: bool = False

    def __post_init__(self) -> None:
        self.parser = Parser(self.protocol)

    def read(self, timeout: float) -> bytes:
        if self.period:
            time.sleep(min(timeout, self.period))
        frame = next(self.frames, None)
        if frame is None:
            time.sleep(min(timeout, 0.005))
            return b""
        return self.protocol.encode(frame)

    def write(self, data: bytes) -> None:
        self.sent += [self.protocol.decode(raw.type, raw.payload) for raw in self.parser.feed(data)]

    def close(self) -> None:
        self.closed = True
