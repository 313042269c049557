"""The command protocol as the firmware declares it, read from ``osc_protocol.json``.

Nothing of the wire format is typed here. ``osc_protocol --client`` writes the JSON from the
firmware's own declarations (``scripts/client_protocol.py``; ctest ``client_protocol_json_current``
fails when the copy in this package is stale): the sync pair, the CRC, each frame type's code,
payload length and fields (name, wire type, count), the flags, the names of every code, the arm's
limits and named poses, the parameter table, and the capture's signals and sizes. The package's copy
is the default arm's (the PUMA 560); a board built for another arm takes its own build's file
(``BUILD/clients/osc_protocol.json``), given as the path here or in the environment variable
``OSC_PROTOCOL``.

A frame on the wire (docs/protocol.md, "Framing and resynchronisation")::

    sync[0] sync[1] | type  length | payload (length bytes, little-endian) | CRC-16 (little-endian)
                      \\___________ CRC over these ____________________/
"""
from __future__ import annotations

import dataclasses
import json
import os
import struct
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import Any, Union

from .errors import ClientError
from .frames import FRAME_CLASSES, Floats, Frame, FrameType

PROTOCOL_JSON = str(Path(__file__).with_name("osc_protocol.json"))
"""The default arm's protocol description, installed with the package."""

WIRE_FORMAT = {"u8": "B", "i16": "h", "u32": "I", "i32": "i", "f32": "f"}
"""The ``struct`` format character of each wire type of the declaration."""

FieldValue = Union[int, float, tuple[int, ...], tuple[float, ...]]


def protocol_path() -> str:
    """The protocol description to read: ``$OSC_PROTOCOL`` when set, else the package's (the default arm's)."""
    return os.environ.get("OSC_PROTOCOL") or PROTOCOL_JSON


def crc16(data: bytes, poly: int, init: int) -> int:
    """The frame's CRC-16 (MSB first, no final XOR: CCITT-FALSE with the declaration's poly and init)."""
    crc = init
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ poly) if crc & 0x8000 else (crc << 1)
            crc &= 0xFFFF
    return crc


class NameList(str, Enum):
    """The lists of names the declaration gives, a code being the index of its name."""

    VERBS = "verbs"
    MOTION_STATES = "motion_states"
    REASONS = "reasons"
    OUTCOMES = "outcomes"
    STOP_CATEGORIES = "stop_categories"
    COMPLETIONS = "completions"
    POSES = "poses"
    FAULTS = "faults"  # bit numbers, not codes: Protocol.fault_names
    PARAM_OPS = "param_ops"
    PARAM_STATUSES = "param_statuses"
    IDENTIFY_STATUSES = "identify_statuses"  # an identify frame's status: ok, or why there is no estimate
    CAPTURE_OPS = "capture_ops"  # a capture frame's op: arm, trigger, abort, status, read
    CAPTURE_TRIGGERS = "capture_triggers"  # what ends an armed capture's pre-trigger
    CAPTURE_STATES = "capture_states"  # where a capture is: idle, armed, triggered, done
    CAPTURE_STATUSES = "capture_statuses"  # a capture_data frame's status: ok, or why the request was refused


NESTED_LISTS = {NameList.PARAM_OPS: ("parameters", "ops"), NameList.PARAM_STATUSES: ("parameters", "statuses"),
                NameList.CAPTURE_OPS: ("capture", "ops"), NameList.CAPTURE_TRIGGERS: ("capture", "triggers"),
                NameList.CAPTURE_STATES: ("capture", "states"), NameList.CAPTURE_STATUSES: ("capture", "statuses")}
"""The lists the declaration keeps inside an object of their own: (the object's key, the list's key)."""


@dataclass(frozen=True)
class Field:
    """One field of a frame: its name, wire type (u8, i16, u32, i32, f32), element count and unit as the firmware
    declares it (``"m, rad"``: the elements in equal runs, the first run in m, the next in rad; ``""`` for codes and
    counts)."""

    name: str
    type: str
    count: int
    unit: str = ""

    def unit_of(self, index: int) -> str:
        """Element ``index``'s unit: the declared units split into equal runs of the elements ("" when they do not
        divide the count)."""
        units = [u.strip() for u in self.unit.split(",")] if self.unit else []
        if not units or self.count % len(units) != 0 or not 0 <= index < self.count:
            return ""
        return units[index // (self.count // len(units))]


@dataclass(frozen=True)
class FrameSpec:
    """A frame type as declared: its code, payload length and fields, and their ``struct`` layout."""

    type: FrameType
    code: int
    payload: int
    fields: tuple[Field, ...]
    layout: struct.Struct


@dataclass(frozen=True)
class Parameter:
    """A runtime parameter of the firmware's table (docs/protocol.md, "Parameters")."""

    name: str
    index: int
    count: int  # elements
    unit: str
    lo: Floats
    hi: Floats
    default: Floats
    access: str  # always, or torque_off: written only with the torque off
    persists: bool  # kept by save


@dataclass(frozen=True)
class CaptureSignal:
    """A signal the board's capture records (docs/protocol.md, "Capture"): its name, its elements (0 to
    ``elements`` - 1) and their unit as the firmware declares it (``"m, rad"``: equal runs, as a field's)."""

    name: str
    code: int  # its index in the declaration: a capture frame's signal
    elements: int
    unit: str

    def unit_of(self, element: int) -> str:
        """Element ``element``'s unit (``Field.unit_of``'s convention)."""
        return Field(self.name, "f32", self.elements, self.unit).unit_of(element)


@dataclass(frozen=True)
class CaptureSpec:
    """The board's capture: the channels it records at once, the values its buffer holds (the samples per channel
    are ``values // channels``), the values a capture_data frame carries, and the signals it can record."""

    channels: int
    values: int
    chunk: int
    signals: tuple[CaptureSignal, ...]

    def signal(self, name: str) -> CaptureSignal | None:
        """The signal of that name, or None."""
        return next((s for s in self.signals if s.name == name), None)

    def depth(self, channels: int) -> int:
        """The samples per channel a capture of ``channels`` channels holds (at most)."""
        return self.values // channels if channels > 0 else 0


@dataclass(frozen=True)
class MotionLimits:
    """The arm's configured maxima of a move: speed, acceleration, jerk."""

    linear: Floats  # m/s, m/s^2, m/s^3
    angular: Floats  # rad/s, rad/s^2, rad/s^3


class Protocol:
    """The command protocol of one firmware build: frames, flags, names, limits, parameters.

    ``Protocol()`` reads ``protocol_path()``; ``Protocol(path)`` a given description. A missing or
    malformed file, or one declaring a frame this package's classes do not match, is a ClientError.
    """

    def __init__(self, path: str | None = None) -> None:
        path = protocol_path() if path is None else path
        if not path:
            raise ClientError("the protocol's description: an empty path (--protocol FILE)")
        try:
            with open(path) as f:
                declaration = json.load(f)
        except (OSError, ValueError) as e:
            raise ClientError(f"{path}: cannot read the protocol's description: {e}") from e
        try:
            self._load(declaration)
        except (KeyError, TypeError, ValueError, struct.error) as e:
            raise ClientError(f"{path}: not a protocol description this client reads: {e!r}") from e

    def _load(self, p: dict[str, Any]) -> None:
        self.sync = bytes(p["sync"])
        self.crc_poly, self.crc_init = int(p["crc"]["poly"]), int(p["crc"]["init"])
        self.control_hz = int(p["control_hz"])
        self.frames: dict[FrameType, FrameSpec] = {}
        for t in p["types"]:
            kind = FrameType(t["name"])
            fields = tuple(Field(str(f["name"]), str(f["type"]), int(f["count"]), str(f.get("unit", "")))
                           for f in p["fields"][kind.value])
            layout = struct.Struct("<" + "".join(f"{f.count}{WIRE_FORMAT[f.type]}" for f in fields))
            if layout.size != t["payload"]:
                raise ValueError(f"the {kind.value} frame's fields do not add up to its payload")
            _check_class(kind, fields)
            self.frames[kind] = FrameSpec(kind, int(t["code"]), int(t["payload"]), fields, layout)
        self.by_code = {spec.code: spec for spec in self.frames.values()}
        self.command_flags = _flags(p["command_flags"])
        self.setpoint_flags = _flags(p["setpoint_flags"])
        self.stream_max_period = int(p["stream_max_period"])
        self.limits = MotionLimits(tuple(map(float, p["limits"]["linear"])), tuple(map(float, p["limits"]["angular"])))
        params = p["parameters"]
        self.param_layout = int(params["layout"])
        self.param_flags = _flags(params["flags"])
        self.parameters = tuple(
            Parameter(str(q["name"]), int(q["index"]), int(q["count"]), str(q["unit"]), tuple(map(float, q["lo"])),
                      tuple(map(float, q["hi"])), tuple(map(float, q["default"])), str(q["access"]),
                      bool(q["persists"]))
            for q in params["table"])
        c = p["capture"]
        self.capture = CaptureSpec(int(c["channels"]), int(c["values"]), int(c["chunk"]), tuple(
            CaptureSignal(str(q["name"]), code, int(q["elements"]), str(q.get("unit", "")))
            for code, q in enumerate(c["signals"])))
        lists = {kind: p[NESTED_LISTS[kind][0]][NESTED_LISTS[kind][1]] if kind in NESTED_LISTS else p[kind.value]
                 for kind in NameList}
        self._names = {kind: [str(n) for n in names] for kind, names in lists.items()}

    # ------------------------------------------------------------------ names and flags
    def names(self, kind: NameList) -> list[str]:
        """The names of a list, in code order."""
        return list(self._names[kind])

    def name_of(self, kind: NameList, code: int) -> str:
        """A code's name; ``?`` for a code outside the list."""
        names = self._names[kind]
        return names[code] if 0 <= code < len(names) else "?"

    def code_of(self, kind: NameList, name: str) -> int:
        """A name's code (ValueError for a name not in the list)."""
        return self._names[kind].index(name)

    @property
    def poses(self) -> list[str]:
        """The arm's named poses (declare_pose)."""
        return self.names(NameList.POSES)

    def fault_names(self, bits: int) -> str:
        """Fault bits as oscctl prints them: ``none``, or the names joined by commas."""
        if bits == 0:
            return "none"
        faults = self._names[NameList.FAULTS]
        return ",".join(faults[i] if i < len(faults) else f"bit{i}" for i in range(32) if bits >> i & 1)

    def parameter(self, name: str) -> Parameter | None:
        """The parameter of that name, or None."""
        return next((q for q in self.parameters if q.name == name), None)

    # ------------------------------------------------------------------ frames
    def crc16(self, data: bytes) -> int:
        """The CRC of a frame's type, length and payload."""
        return crc16(data, self.crc_poly, self.crc_init)

    def payload_length(self, code: int) -> int | None:
        """The payload length of a type code, None for a code the protocol does not declare."""
        spec = self.by_code.get(code)
        return spec.payload if spec else None

    def encode(self, frame: Frame) -> bytes:
        """A frame's bytes on the wire: sync pair, type, length, payload, CRC."""
        spec = self.frames[frame.TYPE]
        flat: list[int | float] = []
        for f in spec.fields:
            value = getattr(frame, f.name)
            if isinstance(value, tuple):
                if not value:
                    value = (0,) * f.count
                if len(value) != f.count:
                    raise ClientError(f"{spec.type.value}.{f.name}: {f.count} values, not {len(value)}")
                flat += value
            else:
                flat.append(value)
        try:
            payload = spec.layout.pack(*flat)
        except struct.error as e:
            raise ClientError(f"{spec.type.value}: {e}") from e
        body = bytes([spec.code, len(payload)]) + payload
        return self.sync + body + struct.pack("<H", self.crc16(body))

    def decode(self, kind: FrameType, payload: bytes) -> Frame:
        """A frame of the given type from its payload (the parser's frames have a valid length)."""
        spec = self.frames[kind]
        values = spec.layout.unpack(payload)
        fields: dict[str, FieldValue] = {}
        for f in spec.fields:
            fields[f.name] = values[0] if f.count == 1 else tuple(values[:f.count])
            values = values[f.count:]
        return FRAME_CLASSES[kind](**fields)


def int_range(wire_type: str) -> tuple[int, int]:
    """The smallest and largest value of an integer wire type (u8: 0 to 255, i16: -32768 to 32767 ...)."""
    fmt = WIRE_FORMAT[wire_type]
    bits = 8 * struct.calcsize("<" + fmt)
    return (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if fmt.islower() else (0, (1 << bits) - 1)


def _flags(names: list[str]) -> dict[str, int]:
    """Each flag's bit: the declaration lists them from bit 0."""
    return {str(n): 1 << i for i, n in enumerate(names)}


def _check_class(kind: FrameType, fields: tuple[Field, ...]) -> None:
    """The frame's class names exactly the declared fields, a tuple for several elements, a float for f32."""
    members = {f.name: f for f in dataclasses.fields(FRAME_CLASSES[kind])}
    if set(members) != {f.name for f in fields}:
        raise ValueError(f"the {kind.value} frame declares fields {[f.name for f in fields]}, this client's "
                         f"{kind.value} class has {list(members)}: update osc_client/frames.py")
    for f in fields:
        default = members[f.name].default
        several, real = isinstance(default, tuple), isinstance(default, float)
        if several != (f.count > 1) or (not several and real != (f.type == "f32")):
            raise ValueError(f"{kind.value}.{f.name}: declared {f.count} x {f.type}, this client's class "
                             f"holds {default!r}")
