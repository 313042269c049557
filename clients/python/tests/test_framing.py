"""Framing, the CRC and the parser's resynchronisation (docs/protocol.md, "Framing and resynchronisation")."""
from __future__ import annotations

import pytest

from osc_client import Answer, Command, FrameType, NameList, Parser, Protocol, RawFrame, State, crc16

# docs/protocol.md, "Command protocol examples" (generated from the firmware's own encoder): command 7,
# a relative move_to by (0.05, 0, -0.02) m with period 1, and its answer: accepted in tick 1234, state
# moving, one move queued.
DOC_COMMAND = bytes.fromhex(
    "A55A0337070000000301CDCC4C3D0000" "00000AD7A3BC00000000000000000000" "00000000000000000000000000000000"
    "00000000000000000000011A08")
DOC_ANSWER = bytes.fromhex("A55A041C070000000301000000000000" "000000000000000000020001D2040000" "6165")


def frames_of(p: Protocol) -> list[bytes]:
    """One frame of each kind the client reads or writes."""
    return [p.encode(Command(id=7, verb=3, flags=1, position=(0.05, 0.0, -0.02), period=1)), DOC_ANSWER,
            p.encode(State(state=2, faults=1 << 11, running_id=99, tick=4321))]


def test_crc_is_ccitt_false(protocol: Protocol) -> None:
    assert (protocol.crc_poly, protocol.crc_init) == (0x1021, 0xFFFF)
    assert protocol.crc16(b"123456789") == 0x29B1  # the standard check value of CRC-16/CCITT-FALSE
    assert crc16(b"", 0x1021, 0xFFFF) == 0xFFFF
    assert protocol.crc16(b"\x00") != protocol.crc16(b"\x01")


def test_frame_layout(protocol: Protocol) -> None:
    frame = protocol.encode(State(tick=5))
    spec = protocol.frames[FrameType.STATE]
    assert frame[:2] == protocol.sync == b"\xa5\x5a"
    assert frame[2] == spec.code and frame[3] == spec.payload
    assert len(frame) == 2 + 2 + spec.payload + 2
    assert int.from_bytes(frame[-2:], "little") == protocol.crc16(frame[2:-2])


def test_encodes_the_documented_command(protocol: Protocol) -> None:
    move = Command(id=7, verb=protocol.code_of(NameList.VERBS, "move_to"), flags=protocol.command_flags["relative"],
                   position=(0.05, 0.0, -0.02), period=1)
    assert protocol.encode(move) == DOC_COMMAND


def test_decodes_the_documented_answer(protocol: Protocol) -> None:
    (raw,) = Parser(protocol).feed(DOC_ANSWER)
    a = protocol.decode(raw.type, raw.payload)
    assert isinstance(a, Answer)
    assert (a.id, a.tick, a.queued) == (7, 1234, 1)
    assert protocol.name_of(NameList.VERBS, a.verb) == "move_to"
    assert protocol.name_of(NameList.OUTCOMES, a.outcome) == "accepted"
    assert protocol.name_of(NameList.MOTION_STATES, a.state) == "moving"


@pytest.mark.parametrize("garbage", [b"", b"\x00\x11\xa5", b"\xa5\xa5", b"\xa5\x5a\x03\x37\x01",
                                     b"\xa5\x5a\xff\x02junk", b"\x5a\xa5\x5a\x04"])
def test_resynchronises_at_every_cut_point(protocol: Protocol, garbage: bytes) -> None:
    """Garbage (junk, a lone sync byte, a false sync pair with a frame's header), then a valid frame
    fed in two pieces split at every byte: the frame comes out exactly once, whole."""
    for frame in frames_of(protocol):
        stream = garbage + frame
        expected = [RawFrame(protocol.by_code[frame[2]].type, frame[4:-2])]
        for cut in range(len(stream) + 1):
            parser = Parser(protocol)
            got = parser.feed(stream[:cut]) + parser.feed(stream[cut:])
            if got != expected:  # a false header can hold the frame back until the in-frame timeout
                got += parser.expire() + parser.expire()
            assert got == expected, f"cut at {cut} of {len(stream)}"


def test_byte_by_byte(protocol: Protocol) -> None:
    parser = Parser(protocol)
    stream = b"".join(frames_of(protocol)) * 2
    got = [f for b in stream for f in parser.feed(bytes([b]))]
    assert [f.type for f in got] == [FrameType.COMMAND, FrameType.ANSWER, FrameType.STATE] * 2


def test_a_frame_inside_a_bad_one_is_found(protocol: Protocol) -> None:
    """A frame whose CRC fails gives up its sync pair only: a good frame within its bytes is found."""
    good = protocol.encode(State(tick=77))
    bad = bytearray(protocol.encode(Command(id=1)))
    bad[-1] ^= 0xFF  # a bad CRC
    inner = bad[:4] + good + bad[4 + len(good):]  # a good frame starts inside the bad one's payload
    got = Parser(protocol).feed(bytes(inner) + good)
    assert [f.type for f in got] == [FrameType.STATE, FrameType.STATE]


def test_unknown_type_and_wrong_length_are_skipped(protocol: Protocol) -> None:
    good = protocol.encode(State(tick=1))
    unknown = b"\xa5\x5a\x7f\x02\x00\x00\x00\x00"
    wrong_length = b"\xa5\x5a" + bytes([good[2], good[3] - 1]) + good[4:]
    got = Parser(protocol).feed(unknown + wrong_length + good)
    assert got == [RawFrame(FrameType.STATE, good[4:-2])]


def test_a_frame_cut_short_loses_not_the_next(protocol: Protocol) -> None:
    """Half a command, the in-frame timeout, then a whole one: the whole one only."""
    cut = protocol.encode(Command(id=1, verb=1))
    whole = protocol.encode(Command(id=2, verb=6))
    parser = Parser(protocol)
    assert parser.feed(cut[: len(cut) // 2]) == []
    assert parser.expire() == []
    (got,) = parser.feed(whole)
    command = protocol.decode(got.type, got.payload)
    assert isinstance(command, Command) and command.id == 2


def test_expire_without_a_frame_begun_is_nothing(protocol: Protocol) -> None:
    parser = Parser(protocol)
    assert parser.feed(b"\x00\x01") == [] and parser.expire() == []
    assert parser.feed(protocol.encode(State())) != []
