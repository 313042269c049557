"""The board's capture, its oscilloscope (docs/protocol.md, "Capture"; ``osc-client capture``).

The board records up to ``CaptureSpec.channels`` channels, each an element of a signal it declares
(``residual[1]``, ``error[0]``, ``stage_cycles[3]`` ...), every tick (or every ``divider`` ticks) into a
buffer of its own, keeps ``pre`` samples before its trigger's (a fault latched, a command accepted, a
channel crossing a level, or a trigger request) and fills the rest of the buffer after it; the client then
reads it out, ``CaptureSpec.chunk`` values a frame. Each request is a ``capture`` frame, answered at once by
a ``capture_data`` frame with its id. The signals, their elements and units, the ops, triggers, states and
statuses are the firmware's, read from ``osc_protocol.json`` (``Protocol.capture``, ``NameList.CAPTURE_*``).

As a module::

    from osc_client import Client
    from osc_client.capture import Oscilloscope
    scope = Oscilloscope(Client("/dev/pts/7"))
    scope.arm([("residual", 1), ("residual_threshold", 1)], trigger="fault", pre=200)
    scope.wait_done(30)                    # the last status; its state done once the fault came
    result = scope.read()                  # result.ticks, result.times(), result.values[c], result.names
"""
from __future__ import annotations

import csv
import re
import time
from dataclasses import dataclass
from typing import Any, Sequence, TextIO, Union

from .client import Client
from .errors import ClientError
from .frames import Capture, CaptureData, FrameType
from .protocol import CaptureSignal, NameList, Protocol, int_range
from .record import f32_text

_NAME = re.compile(r"([A-Za-z_]\w*)(?:\[(\d+)\])?\Z")

MANUAL = "manual"
"""The trigger of a capture triggered by a request (``Oscilloscope.trigger``) alone."""

OK = "ok"
"""The status of a request done as asked (the first of the declaration's statuses)."""

DONE = "done"
"""The state of a capture whose buffer holds it."""

WAITING = ("armed", "triggered")
"""The states of a capture on its way to done."""

STATUS_POLL = 0.05
"""Seconds between two status requests while waiting for a capture to be done."""

STATE_FRAME_WAIT = 1.0
"""Seconds ``wait_ticks`` waits for a state frame (the board's tick) before it takes the wall's time instead."""


@dataclass(frozen=True)
class CaptureChannel:
    """A channel of a capture: an element of a signal the board declares."""

    signal: CaptureSignal
    element: int

    @property
    def name(self) -> str:
        """``residual[1]``."""
        return f"{self.signal.name}[{self.element}]"

    @property
    def unit(self) -> str:
        """The element's unit (``"N m"``, ``"m"``; "" when the declaration gives none)."""
        return self.signal.unit_of(self.element)

    @property
    def column(self) -> str:
        """Its CSV column's name: ``residual[1] [N m]`` (the name alone without a unit)."""
        return f"{self.name} [{self.unit}]" if self.unit else self.name


ChannelLike = Union[CaptureChannel, str, tuple[str, int]]
"""A channel as given: a CaptureChannel, a name (``residual[1]``) or a signal's name and an element."""


def capture_signals_text(p: Protocol) -> str:
    """The signals' names in short: ``error[0..5], observer_error[0..5], ..., stage_cycles[0..7]``."""
    return ", ".join(s.name if s.elements == 1 else f"{s.name}[0..{s.elements - 1}]" for s in p.capture.signals)


def parse_channel(p: Protocol, text: str) -> CaptureChannel:
    """The channel of a name, ``signal[k]`` (a signal of one element: its name alone, element 0). A ClientError
    names what is wrong: an unknown signal (with the valid ones), an element out of range, a missing one."""
    m = _NAME.match(text.strip())
    signal = p.capture.signal(m.group(1)) if m else None
    if m is None or signal is None:
        raise ClientError(f"no capture signal '{text}': the signals are {capture_signals_text(p)}")
    n = signal.elements
    if m.group(2) is None:
        if n != 1:
            raise ClientError(f"capture signal {text}: {signal.name} has {n} elements: name one, "
                              f"{signal.name}[0..{n - 1}]")
        return CaptureChannel(signal, 0)
    element = int(m.group(2))
    if element >= n:
        raise ClientError(f"capture signal {text}: {signal.name} has {n} element" + ("s" if n > 1 else "") +
                          f", {signal.name}[0..{n - 1}]")
    return CaptureChannel(signal, element)


def channel_of(p: Protocol, c: ChannelLike) -> CaptureChannel:
    """A channel as given (``ChannelLike``), checked as ``parse_channel`` checks a name."""
    if isinstance(c, CaptureChannel):
        return c
    return parse_channel(p, c if isinstance(c, str) else f"{c[0]}[{c[1]}]")


def parse_channels(p: Protocol, names: Sequence[ChannelLike]) -> list[CaptureChannel]:
    """The channels of several names, in order (a ClientError for none, or more than the board records)."""
    channels = [channel_of(p, n) for n in names]
    if not 1 <= len(channels) <= p.capture.channels:
        raise ClientError(f"capture: 1 to {p.capture.channels} channels, not {len(channels)}")
    return channels


class CaptureRefused(ClientError):
    """A capture request the board refused: ``status`` is the refusal's name (``bad_span``, ``not_done`` ...)."""

    def __init__(self, op: str, status: str, answer: CaptureData) -> None:
        super().__init__(f"capture {op}: refused: {status}")
        self.op, self.status, self.answer = op, status, answer


@dataclass(frozen=True)
class CaptureResult:
    """A done capture as read: each sample's tick and each channel's values, in the channels' order.

    Sample s is at tick ``first_tick + s * divider`` (``ticks[s]``: ``first_tick`` is the low 32 bits of the
    board's count, the ticks counted on from it) and at ``times()[s]`` seconds from the trigger's sample, which
    is sample ``pre``.
    """

    channels: tuple[CaptureChannel, ...]
    values: tuple[tuple[float, ...], ...]  # values[c][s]: channel c's sample s, in its unit
    depth: int  # samples per channel
    pre: int  # samples before the trigger's
    divider: int  # ticks between two samples
    trigger_tick: int
    first_tick: int
    trigger: str  # what triggered it (NameList.CAPTURE_TRIGGERS)
    control_hz: float  # ticks per second

    @property
    def ticks(self) -> list[int]:
        """Each sample's tick."""
        return [self.first_tick + s * self.divider for s in range(self.depth)]

    def times(self) -> list[float]:
        """Each sample's time from the trigger's sample [s] (the board's time: ticks / control rate)."""
        return [(s - self.pre) * self.divider / self.control_hz for s in range(self.depth)]

    @property
    def names(self) -> list[str]:
        """The channels' names: ``residual[1]`` ..."""
        return [c.name for c in self.channels]

    @property
    def units(self) -> list[str]:
        """The channels' units."""
        return [c.unit for c in self.channels]

    def header(self) -> list[str]:
        """The CSV's header: ``tick``, ``t [s]`` (from the trigger), then a column per channel, its name and unit
        (``residual[1] [N m]``)."""
        return ["tick", "t [s]"] + [c.column for c in self.channels]

    def rows(self) -> list[list[str]]:
        """The CSV's rows, a sample each: its tick, its time from the trigger, each channel's value (the shortest
        text that reads back as the same 32-bit float)."""
        return [[str(tick), repr(t)] + [f32_text(v[s]) for v in self.values]
                for s, (tick, t) in enumerate(zip(self.ticks, self.times()))]

    def write_csv(self, out: TextIO) -> None:
        """The capture as CSV: the header, then a row per sample."""
        w = csv.writer(out, lineterminator="\n")
        w.writerow(self.header())
        w.writerows(self.rows())


class Oscilloscope:
    """The board's capture over a client: each method sends one request (or, ``read``, as many as the values
    need) and waits for its answer, up to ``timeout`` seconds each (then a ClientError).

    ``arm``, ``trigger``, ``abort`` and ``status`` return the answer (``CaptureData``): its ``status`` tells a
    refusal (``status_name``), its ``state`` where the capture is (``state_name``).
    """

    def __init__(self, client: Client, timeout: float = 5.0) -> None:
        self.client = client
        self.protocol = client.protocol
        self.timeout = timeout
        fields = {f.name: f for f in self.protocol.frames[FrameType.CAPTURE].fields}
        self._slots = fields["signal"].count  # the frame's channel slots
        self._divider = int_range(fields["divider"].type)

    # ------------------------------------------------------------------ names
    def status_name(self, a: CaptureData) -> str:
        """The answer's status: ``ok``, or why the request was refused."""
        return self.protocol.name_of(NameList.CAPTURE_STATUSES, a.status)

    def state_name(self, a: CaptureData) -> str:
        """The capture's state after the request: idle, armed, triggered, done."""
        return self.protocol.name_of(NameList.CAPTURE_STATES, a.state)

    def ok(self, a: CaptureData) -> bool:
        """The request was done as asked."""
        return self.status_name(a) == OK

    # ------------------------------------------------------------------ requests
    def request(self, op: str, **fields: Any) -> CaptureData:
        """One capture frame of op ``op`` (NameList.CAPTURE_OPS) and ``fields`` (Capture's), and its answer."""
        code = self.protocol.code_of(NameList.CAPTURE_OPS, op)
        return self.client.capture(Capture(op=code, **fields), self.timeout)

    def arm(self, channels: Sequence[ChannelLike], trigger: str = MANUAL, pre: int = 0, divider: int = 1,
            level_channel: int = 0, level: float = 0.0) -> CaptureData:
        """Arms a capture of ``channels`` (each a ``ChannelLike``: ``"residual[1]"``, ``("error", 0)``), ended by
        ``trigger`` (NameList.CAPTURE_TRIGGERS; rising and falling: channel ``level_channel`` crossing
        ``level``), ``pre`` samples kept before the trigger's, a sample every ``divider`` ticks. A capture armed
        or done before is dropped. The answer (refused: bad_channel, bad_trigger, bad_span ...)."""
        p = self.protocol
        chosen = parse_channels(p, channels)
        triggers = p.names(NameList.CAPTURE_TRIGGERS)
        if trigger not in triggers:
            raise ClientError(f"capture trigger '{trigger}': one of {', '.join(triggers)}")
        lo, hi = self._divider
        if not max(lo, 1) <= divider <= hi:
            raise ClientError(f"capture divider {divider}: 1 to {hi}")
        pad = (0,) * (self._slots - len(chosen))
        return self.request("arm", channels=len(chosen), signal=tuple(c.signal.code for c in chosen) + pad,
                            element=tuple(c.element for c in chosen) + pad,
                            trigger=p.code_of(NameList.CAPTURE_TRIGGERS, trigger), level_channel=level_channel,
                            level=float(level), pre=pre, divider=divider)

    def trigger(self) -> CaptureData:
        """Triggers the armed capture now, whatever its trigger (refused not_armed when none is armed): the sample
        after this request is the trigger's."""
        return self.request("trigger")

    def abort(self) -> CaptureData:
        """Stops and drops the capture: idle."""
        return self.request("abort")

    def status(self) -> CaptureData:
        """The capture's state and set-up, nothing changed."""
        return self.request("status")

    def read(self) -> CaptureResult:
        """A done capture's values: ``read`` requests from offset 0 on, each answered with up to
        ``CaptureSpec.chunk`` values, until all ``depth x channels`` are in. A refusal (not_done: the capture is
        not done) raises CaptureRefused; a capture that changes while read (armed again) a ClientError."""
        p = self.protocol
        values: list[float] = []
        first: CaptureData | None = None
        total = 0
        while first is None or len(values) < total:
            a = self.request("read", offset=len(values))
            if not self.ok(a):
                raise CaptureRefused("read", self.status_name(a), a)
            if first is None:
                first, total = a, a.depth * a.channels
            elif _setup(a) != _setup(first):
                raise ClientError("capture read: the capture changed while it was read (armed again?)")
            if a.offset != len(values) or (a.count == 0 and len(values) < total) or a.count > len(a.values):
                raise ClientError(f"capture read: asked for the values from {len(values)}, the answer holds "
                                  f"{a.count} from {a.offset} (of {total})")
            values += a.values[:a.count]
        assert first is not None
        n = first.channels
        if not 1 <= n <= len(first.signal):
            raise ClientError(f"capture read: a done capture of {n} channels")
        channels = []
        for code, element in zip(first.signal[:n], first.element[:n]):
            if not 0 <= code < len(p.capture.signals) or element >= p.capture.signals[code].elements:
                raise ClientError(f"capture read: the board's channel of signal {code}, element {element}: not in "
                                  "this protocol's signals (another build's board?)")
            channels.append(CaptureChannel(p.capture.signals[code], element))
        return CaptureResult(
            tuple(channels), tuple(tuple(values[c:total:n]) for c in range(n)), first.depth, first.pre,
            max(first.divider, 1), first.trigger_tick, first.first_tick,
            p.name_of(NameList.CAPTURE_TRIGGERS, first.trigger), float(p.control_hz))

    # ------------------------------------------------------------------ waiting
    def wait_done(self, timeout: float, poll: float = STATUS_POLL) -> CaptureData:
        """Status requests every ``poll`` seconds (the board's frames read between them, the link kept alive)
        until the capture is done or no longer on its way (idle: aborted, or armed again and refused), or
        ``timeout`` seconds have passed: the last answer."""
        deadline = time.monotonic() + timeout
        while True:
            a = self.status()
            left = deadline - time.monotonic()
            if self.state_name(a) not in WAITING or left <= 0:
                return a
            self.client.pump(min(poll, left))

    def wait_ticks(self, ticks: int, timeout: float) -> None:
        """Waits until ``ticks`` ticks of the board's have passed (up to ``timeout`` seconds): counted on the
        state frames' ticks; a board that sends none within STATE_FRAME_WAIT seconds is taken to tick at its
        control rate in the wall's time. A board run faster than real time (osc_sim --speed) takes less."""
        c = self.client
        start = time.monotonic()
        first = c.state(min(timeout, STATE_FRAME_WAIT))
        if first is None:
            c.pump(min(ticks / self.protocol.control_hz, max(0.0, timeout - (time.monotonic() - start))))
            return
        tick0 = first.tick

        def passed() -> bool:
            s = c.latest_state
            return s is not None and (s.tick - tick0) % (1 << 32) >= ticks

        c.pump(max(0.0, timeout - (time.monotonic() - start)), passed)


def _setup(a: CaptureData) -> tuple[object, ...]:
    """What a done capture's answers to its reads all tell alike."""
    return (a.channels, a.signal, a.element, a.divider, a.depth, a.pre, a.trigger_tick, a.first_tick)
