"""Every frame type's round trip, and the checks of the protocol description."""
from __future__ import annotations

import dataclasses
import json
import struct
from pathlib import Path
from typing import Any

import pytest

from osc_client import PROTOCOL_JSON, ClientError, Frame, FrameType, Identify, NameList, Parser, Protocol, State
from osc_client.frames import FRAME_CLASSES
from osc_client.protocol import Field, FieldValue

EXTREMES = {"u8": (0, 255), "i16": (-32768, 32767), "u32": (0, 2**32 - 1), "i32": (-(2**31), 2**31 - 1)}


def sample(f: Field, seed: int) -> FieldValue:
    """A value of the field unlike its neighbours': the wire type's extremes and numbers between,
    floats exact in f32."""
    def one(k: int) -> int | float:
        if f.type == "f32":
            return (seed + k) * 0.5 - 3.25
        lo, hi = EXTREMES[f.type]
        return (lo, hi, (lo + hi) // 2 + seed + k)[(seed + k) % 3]
    return tuple(one(k) for k in range(f.count)) if f.count > 1 else one(0)


def sample_frame(p: Protocol, kind: FrameType) -> Frame:
    spec = p.frames[kind]
    return FRAME_CLASSES[kind](**{f.name: sample(f, n) for n, f in enumerate(spec.fields)})


def test_every_declared_type_has_its_class(protocol: Protocol) -> None:
    assert set(protocol.frames) == set(FrameType)
    assert {spec.code for spec in protocol.frames.values()} == set(protocol.by_code)


@pytest.mark.parametrize("kind", list(FrameType))
def test_round_trip(protocol: Protocol, kind: FrameType) -> None:
    frame = sample_frame(protocol, kind)
    data = protocol.encode(frame)
    assert len(data) == protocol.frames[kind].payload + 6
    (raw,) = Parser(protocol).feed(data)
    assert raw.type == kind
    assert protocol.decode(raw.type, raw.payload) == frame


def test_identify_frame_round_trip_and_layout(protocol: Protocol) -> None:
    """The identify frame (code 11, 217 bytes: docs/protocol.md, "Identify frame"): its fields at the documented
    offsets, and back through the parser after a false header of its own type."""
    f = Identify(id=0xDEADBEEF, status=protocol.code_of(NameList.IDENTIFY_STATUSES, "prediction_error"),
                 samples=16000, lost=3, condition=1234.5, prediction_error=0.125,
                 friction=tuple(0.25 * k - 2.0 for k in range(18)), friction_sd=tuple(0.0625 * k for k in range(18)),
                 identified=1 << 0 | 1 << 17, armature=(0.25, -0.125, 0.0625, 0.5, 1.5, -2.0),
                 armature_sd=(0.0078125,) * 6)
    data = protocol.encode(f)
    assert (len(data), data[2], data[3]) == (223, 11, 217)
    payload = data[4:-2]
    assert struct.unpack_from("<IBIIff", payload, 0) == (0xDEADBEEF, 3, 16000, 3, 1234.5, 0.125)
    assert struct.unpack_from("<f", payload, 21 + 17 * 4) == (0.25 * 17 - 2.0,)  # friction[17]: Stribeck J6
    assert struct.unpack_from("<f", payload, 93 + 4) == (0.0625,)  # friction_sd[1]
    assert struct.unpack_from("<I6f6f", payload, 165) == (1 << 0 | 1 << 17,) + f.armature + f.armature_sd
    false_header = protocol.sync + bytes([11, 217]) + bytes(5)  # the frame's header, then a frame cut short
    frames = Parser(protocol).feed(b"\x00" + false_header + data + data[:100]) + Parser(protocol).feed(data)
    assert [r.type for r in frames] == [FrameType.IDENTIFY, FrameType.IDENTIFY]
    assert all(protocol.decode(r.type, r.payload) == f for r in frames)
    parser = Parser(protocol)
    assert [r for b in data for r in parser.feed(bytes([b]))] == frames[:1]  # byte by byte


def test_identify_statuses(protocol: Protocol) -> None:
    names = ["ok", "too_few_samples", "ill_conditioned", "prediction_error", "not_finite", "aborted"]
    assert protocol.names(NameList.IDENTIFY_STATUSES) == names
    assert protocol.name_of(NameList.IDENTIFY_STATUSES, 6) == "?"


def test_empty_tuples_encode_as_zeros(protocol: Protocol) -> None:
    (raw,) = Parser(protocol).feed(protocol.encode(State()))
    s = protocol.decode(raw.type, raw.payload)
    assert isinstance(s, State)
    assert s.x_d == (0.0,) * 6 and s.link == (0,) * 7 and s.tick == 0


def test_a_wrong_count_or_value_is_a_named_error(protocol: Protocol) -> None:
    with pytest.raises(ClientError, match=r"state\.x_d: 6 values, not 2"):
        protocol.encode(State(x_d=(1.0, 2.0)))
    with pytest.raises(ClientError, match="state"):
        protocol.encode(State(queued=256))  # a u8


def test_names_and_flags(protocol: Protocol) -> None:
    assert protocol.name_of(NameList.REASONS, protocol.code_of(NameList.REASONS, "not_enabled")) == "not_enabled"
    assert protocol.name_of(NameList.REASONS, 999) == "?"
    assert protocol.command_flags["relative"] == 1 and protocol.setpoint_flags["end"] == 1
    assert protocol.fault_names(0) == "none"
    assert protocol.fault_names(0b101) == "non_finite,saturation"
    assert protocol.fault_names(1 << 31) == "bit31"
    assert protocol.poses[0] == "start"
    ks = protocol.parameter("ks")
    assert ks is not None and ks.count == 6 and protocol.parameter("nosuch") is None


def declaration() -> dict[str, Any]:
    result: dict[str, Any] = json.loads(Path(PROTOCOL_JSON).read_text())
    return result


def write(tmp_path: Path, d: dict[str, Any]) -> str:
    path = tmp_path / "osc_protocol.json"
    path.write_text(json.dumps(d))
    return str(path)


def test_a_field_the_classes_do_not_know_is_named(tmp_path: Path) -> None:
    d = declaration()
    d["fields"]["answer"][0]["name"] = "ident"
    with pytest.raises(ClientError, match="update osc_client/frames.py"):
        Protocol(write(tmp_path, d))


def test_an_identify_field_the_class_does_not_know_is_named(tmp_path: Path) -> None:
    d = declaration()
    next(f for f in d["fields"]["identify"] if f["name"] == "armature")["name"] = "inertia"
    with pytest.raises(ClientError, match="the identify frame declares fields .*'inertia'.*update osc_client/frames"):
        Protocol(write(tmp_path, d))


def test_a_layout_that_does_not_add_up_is_named(tmp_path: Path) -> None:
    d = declaration()
    d["fields"]["state"][0]["type"] = "u32"
    with pytest.raises(ClientError, match="do not add up to its payload"):
        Protocol(write(tmp_path, d))


def test_a_type_the_class_does_not_hold_is_named(tmp_path: Path) -> None:
    d = declaration()
    value = next(f for f in d["fields"]["param"] if f["name"] == "value")
    value["type"] = "u32"  # the same size; the class holds a float
    with pytest.raises(ClientError, match=r"param\.value: declared 1 x u32"):
        Protocol(write(tmp_path, d))


@pytest.mark.parametrize("content, message", [(None, "cannot read the protocol's description"),
                                              ("not json", "cannot read the protocol's description"),
                                              ("{}", "not a protocol description this client reads")])
def test_a_bad_file_is_named(tmp_path: Path, content: str | None, message: str) -> None:
    path = tmp_path / "p.json"
    if content is not None:
        path.write_text(content)
    with pytest.raises(ClientError, match=message):
        Protocol(str(path))
    with pytest.raises(ClientError, match="an empty path"):
        Protocol("")


def test_osc_protocol_names_another_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    d = declaration()
    d["poses"] = ["home_pose"]
    monkeypatch.setenv("OSC_PROTOCOL", write(tmp_path, d))
    assert Protocol().poses == ["home_pose"]
    monkeypatch.delenv("OSC_PROTOCOL")
    assert Protocol().poses[0] == "start"


def test_frame_classes_are_frozen() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        State().tick = 1  # type: ignore[misc]


def test_the_state_texts_friction_fit(protocol: Protocol) -> None:
    """The saved friction's check (issue 57): J1 and J2 checked, J2 stale, the others not yet; as oscctl prints it."""
    from osc_client.text import state_text
    text = state_text(protocol, State(x_d=(0.0,) * 6, x=(0.0,) * 6, friction_checked=0x3, friction_stale=0x2))
    assert "friction_fit: J1 fits, J2 stale, J3 -, J4 -, J5 -, J6 -\n" in text
