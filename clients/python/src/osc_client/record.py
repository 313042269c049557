"""State frames as data: CSV columns and rows, and named signals to plot (``osc-client record``, ``plot``).

The columns of a recording are the state frame's fields as ``osc_protocol.json`` declares them, ``tick``
first, then ``t`` (the board's time, ``tick / control_hz`` seconds), then every other field in its
declared order, each vector field expanded into one column per element (``x_d[0]`` .. ``x_d[5]``). The
command link's error counters (``link[0]`` ..: OSC_LINK_ERROR_LIST's order, docs/protocol.md: bad_crc,
bad_header, bad_length, junk_bytes, short_frames, seq_errors, timeouts) are columns too: a recording
holds the whole frame. Codes stay numbers (``state`` 1 is ``Protocol.name_of(NameList.MOTION_STATES, 1)``,
``faults`` the fault bits). A float field is written as the shortest text that reads back as the same
32-bit float (``0.4318``, not ``0.43180000782``).

A signal (``parse_signal``) is one number per state frame, named as a column is:

- a scalar field (``queued``, ``dropped``, ``state`` ...) or a vector field's element (``x[0]``, ``x_d[2]``,
  ``link[1]``), in the field's unit: x and x_d are x, y, z [m] then roll, pitch, yaw [rad]; the others
  are codes and counts (no unit);
- ``error[k]`` (k 0 .. 2): the reference's position minus the measured one along x, y, z,
  ``x_d[k] - x[k]``, in mm;
- ``error``: the position error's norm ``|x_d[0:3] - x[0:3]|``, in mm.

The units are the firmware's, as its field declarations give them (the protocol's JSON: ``Field.unit_of``).

As a module::

    from osc_client import Client, CsvRecorder, Traces, parse_signal
    c = Client("/dev/pts/7")
    with open("run.csv", "w", newline="") as f:
        rec = CsvRecorder(c.protocol, f)       # writes the header
        c.on_state = rec.write                 # a row per state frame, flushed
        c.pump(10)
    traces = Traces(c.protocol, [parse_signal(c.protocol, "error")])
    c.on_state = traces.add
    c.pump(5)                                  # traces.t [s], traces.values[0] [mm]
"""
from __future__ import annotations

import csv
import math
import re
import struct
from collections import deque
from dataclasses import dataclass
from enum import Enum
from typing import Sequence, TextIO, Union

from .errors import ClientError
from .frames import FrameType, State
from .protocol import Field, Protocol

Number = Union[int, float]

ERROR = "error"
"""The derived signals' name: ``error`` (the position error's norm) and ``error[k]`` (along axis k), in mm."""

ERROR_AXES = 3
"""The position error's axes: x, y, z."""

ERROR_UNIT = "mm"

_NAME = re.compile(r"([A-Za-z_]\w*)(?:\[(\d+)\])?\Z")


@dataclass(frozen=True)
class Column:
    """One CSV column of a recording: a state-frame field's element, or the time ``t``."""

    name: str  # the header's: tick, t, state, x_d[0] ...
    field: str  # the State field it reads (t: tick)
    index: int | None  # the element of a vector field; None for a scalar one
    type: str  # the field's wire type (u8, u32, f32 ...); f64 for t, a quotient
    unit: str  # m, rad, s; "" for codes and counts
    divisor: float = 1.0  # t: the control rate (ticks per second)

    def value(self, s: State) -> Number:
        """The column's value in a state frame (a vector field left empty, as a keep-alive's, reads 0)."""
        raw = _element(getattr(s, self.field), self.index)
        return raw / self.divisor if self.type == "f64" else raw

    def text(self, value: Number) -> str:
        """The value as the CSV holds it: an integer's digits; a 32-bit float's shortest text that reads back
        as the same float; another float's ``repr``."""
        if isinstance(value, int):
            return str(value)
        return f32_text(value) if self.type == "f32" else repr(value)


def f32_text(v: float) -> str:
    """The shortest text that reads back as the same 32-bit float (``repr`` for a value no float32 holds)."""
    if math.isfinite(v):
        for digits in range(1, 10):  # 9 significant digits tell any float32
            text = repr(float(f"{v:.{digits}g}"))
            if _f32(float(text)) == v:
                return text
    return repr(v)


def _f32(v: float) -> float:
    try:
        return float(struct.unpack("<f", struct.pack("<f", v))[0])
    except OverflowError:
        return math.nan


def _element(value: object, index: int | None) -> Number:
    if index is None:
        assert isinstance(value, (int, float))
        return value
    assert isinstance(value, tuple)
    element = value[index] if value else 0
    assert isinstance(element, (int, float))
    return element


def _state_fields(p: Protocol) -> tuple[Field, ...]:
    return p.frames[FrameType.STATE].fields


def _unit(f: Field, index: int | None) -> str:
    """Element ``index``'s unit; a whole field's (index None) when it is a single number, else none."""
    if index is None:
        return f.unit_of(0) if f.count == 1 else ""
    return f.unit_of(index)


def state_columns(p: Protocol) -> tuple[Column, ...]:
    """A recording's columns: ``tick``, ``t`` [s], then the state frame's other fields in their declared order,
    a vector field as one column per element (``x[0]`` .. ``x[5]``)."""
    fields = _state_fields(p)
    tick = [f for f in fields if f.name == "tick"]
    columns = [Column("tick", "tick", None, tick[0].type, "")] if tick else []
    if tick:
        columns.append(Column("t", "tick", None, "f64", "s", float(p.control_hz)))
    for f in fields:
        if f.name == "tick":
            continue
        if f.count == 1:
            columns.append(Column(f.name, f.name, None, f.type, _unit(f, None)))
        else:
            columns += [Column(f"{f.name}[{k}]", f.name, k, f.type, _unit(f, k)) for k in range(f.count)]
    return tuple(columns)


def csv_header(p: Protocol) -> list[str]:
    """The header row: each column's name."""
    return [c.name for c in state_columns(p)]


def state_row(columns: Sequence[Column], s: State) -> list[Number]:
    """A state frame's values in the columns' order (``state_columns``)."""
    return [c.value(s) for c in columns]


def csv_row(columns: Sequence[Column], s: State) -> list[str]:
    """A state frame's CSV row: its values as text (``Column.text``) in the columns' order."""
    return [c.text(c.value(s)) for c in columns]


class CsvRecorder:
    """Writes state frames to a CSV file: the header when made, then a row for each frame given to ``write``,
    flushed at once, so that a recording cut short (a signal, a crash) is a file of whole rows.

    Give ``write`` as ``Client.on_state``. ``rows`` counts the rows written.
    """

    def __init__(self, p: Protocol, out: TextIO) -> None:
        self.columns = state_columns(p)
        self.rows = 0
        self._out = out
        self._writer = csv.writer(out, lineterminator="\n")
        self._writer.writerow([c.name for c in self.columns])
        out.flush()

    def write(self, s: State) -> None:
        """One row: the frame's values."""
        self._writer.writerow(csv_row(self.columns, s))
        self._out.flush()
        self.rows += 1


# --------------------------------------------------------------------------- signals
class SignalKind(Enum):
    """What a signal reads."""

    FIELD = "field"  # a field's value or element, in its unit
    ERROR = "error"  # x_d[k] - x[k] [mm]
    ERROR_NORM = "error_norm"  # |x_d[0:3] - x[0:3]| [mm]


@dataclass(frozen=True)
class Signal:
    """A named number of each state frame (``parse_signal``): a field's element, or a derived one."""

    name: str  # as given: x[0], queued, error, error[1]
    unit: str  # m, rad, mm; "" for codes and counts
    kind: SignalKind
    field: str = ""  # FIELD: the State field
    index: int | None = None  # FIELD: the element of a vector field; ERROR: the axis

    def value(self, s: State) -> float:
        """The signal's value in a state frame."""
        if self.kind == SignalKind.FIELD:
            return float(_element(getattr(s, self.field), self.index))
        d = [1000.0 * (_element(s.x_d, k) - _element(s.x, k)) for k in range(ERROR_AXES)]
        if self.kind == SignalKind.ERROR:
            assert self.index is not None
            return d[self.index]
        return math.hypot(*d)


def _has_error(p: Protocol) -> bool:
    counts = {f.name: f.count for f in _state_fields(p)}
    return min(counts.get("x_d", 0), counts.get("x", 0)) >= ERROR_AXES


def signal_names(p: Protocol) -> list[str]:
    """Every signal's name: each field's (vector fields by element, ``tick`` too), then the derived ones."""
    names: list[str] = []
    for f in _state_fields(p):
        names += [f.name] if f.count == 1 else [f"{f.name}[{k}]" for k in range(f.count)]
    if _has_error(p):
        names += [ERROR] + [f"{ERROR}[{k}]" for k in range(ERROR_AXES)]
    return names


def signals_text(p: Protocol) -> str:
    """The signals' names in short: ``state, stop, ..., x_d[0..5], x[0..5], tick, link[0..6], friction_checked,
    friction_stale, error, error[0..2]``."""
    names = [f.name if f.count == 1 else f"{f.name}[0..{f.count - 1}]" for f in _state_fields(p)]
    if _has_error(p):
        names += [ERROR, f"{ERROR}[0..{ERROR_AXES - 1}]"]
    return ", ".join(names)


def parse_signal(p: Protocol, name: str) -> Signal:
    """The signal of a name (the module's docstring lists them); a ClientError names what is wrong: an unknown
    name (with the valid ones), a vector field without an index, a scalar with one, an index out of range."""
    m = _NAME.match(name.strip())
    fields = {f.name: f for f in _state_fields(p)}
    known = m is not None and (m.group(1) in fields or (m.group(1) == ERROR and _has_error(p)))
    if m is None or not known:
        raise ClientError(f"no signal '{name}': the signals are {signals_text(p)}")
    base, index = m.group(1), None if m.group(2) is None else int(m.group(2))
    if base == ERROR and base not in fields:
        if index is None:
            return Signal(ERROR, ERROR_UNIT, SignalKind.ERROR_NORM)
        if index >= ERROR_AXES:
            raise ClientError(f"signal {name}: the position error has {ERROR_AXES} axes, {ERROR}[0..{ERROR_AXES - 1}]"
                              f" (x, y, z); {ERROR} alone is its norm")
        return Signal(f"{ERROR}[{index}]", ERROR_UNIT, SignalKind.ERROR, index=index)
    f = fields[base]
    if f.count == 1:
        if index is not None:
            raise ClientError(f"signal {name}: {base} is a single number: {base}, without an index")
        return Signal(base, _unit(f, None), SignalKind.FIELD, base)
    if index is None:
        raise ClientError(f"signal {name}: {base} has {f.count} elements: name one, {base}[0..{f.count - 1}]")
    if index >= f.count:
        raise ClientError(f"signal {name}: {base} has {f.count} elements, {base}[0..{f.count - 1}]")
    return Signal(f"{base}[{index}]", _unit(f, index), SignalKind.FIELD, base, index)


def parse_signals(p: Protocol, names: Sequence[str]) -> list[Signal]:
    """The signals of several names, in order, each once (``parse_signal``'s errors)."""
    signals: dict[str, Signal] = {}
    for name in names:
        s = parse_signal(p, name)
        signals.setdefault(s.name, s)
    return list(signals.values())


class Traces:
    """The values of signals over the board's time, from state frames: ``t`` [s] (``tick / control_hz``) and,
    for each signal in order, ``values[i]`` in its unit. With ``keep`` only the last ``keep`` seconds of
    board time are kept (a live view's window); without, everything.

    Give ``add`` as ``Client.on_state``. ``frames`` counts the frames added.
    """

    def __init__(self, p: Protocol, signals: Sequence[Signal], keep: float | None = None) -> None:
        self.signals = tuple(signals)
        self.keep = keep
        self.frames = 0
        self.t: deque[float] = deque()
        self.values: tuple[deque[float], ...] = tuple(deque() for _ in self.signals)
        self._hz = float(p.control_hz)

    def add(self, s: State) -> None:
        """A frame's time and signals' values (the oldest dropped beyond ``keep`` seconds)."""
        t = s.tick / self._hz
        self.t.append(t)
        for signal, series in zip(self.signals, self.values):
            series.append(signal.value(s))
        self.frames += 1
        if self.keep is not None:
            while self.t and self.t[0] < t - self.keep:
                self.t.popleft()
                for series in self.values:
                    series.popleft()
