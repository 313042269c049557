"""The board's capture (osc_client.capture): its frames, the declaration's signals and lists, the channels' names,
and the requests against a board's capture in memory (fakes.FakeCapture): arm, trigger, status, abort, the read
loop over the offsets."""
from __future__ import annotations

import io
import json
import struct
from pathlib import Path

import pytest

from fakes import FakeBoard, FakeCapture, ramp
from osc_client import (PROTOCOL_JSON, Capture, CaptureData, CaptureRefused, Client, ClientError, Frame, FrameType,
                        NameList, Oscilloscope, Parser, Protocol, capture_signals_text, parse_channel, parse_channels)
from osc_client.capture import CaptureResult

VALID = ("error[0..5], observer_error[0..5], velocity[0..5], tau[0..5], tau_f_hat[0..5], theta_hat[0..17], "
         "residual[0..5], residual_threshold[0..5], codes[0..5], drive_margin[0..5], stage_cycles[0..7]")


def scope_of(p: Protocol, capture: FakeCapture | None, timeout: float = 2.0) -> tuple[Oscilloscope, FakeBoard]:
    """An oscilloscope over a FakeBoard with the capture (None: one that answers no capture frame)."""
    board = FakeBoard(p, lambda c: [], capture_reply=capture, on_read=capture.clock if capture else None)
    return Oscilloscope(Client(board, protocol=p, keepalive=0.0, first_id=500), timeout), board


def op_names(p: Protocol, board: FakeBoard) -> list[str]:
    return [p.name_of(NameList.CAPTURE_OPS, f.op) for f in board.captures()]


# --------------------------------------------------------------------------- frames and the declaration
def test_the_frames_layouts(protocol: Protocol) -> None:
    """capture (code 12, 37 bytes) and capture_data (code 13, 207 bytes) at docs/protocol.md's offsets, and back
    through the parser."""
    cap = Capture(id=0xDEADBEEF, op=protocol.code_of(NameList.CAPTURE_OPS, "arm"), channels=3,
                  signal=(6, 7, 0, 0, 0, 0, 0, 0), element=(1, 1, 0, 0, 0, 0, 0, 0),
                  trigger=protocol.code_of(NameList.CAPTURE_TRIGGERS, "rising"), level_channel=2, level=-1.5,
                  pre=200, divider=4, offset=123456)
    data = protocol.encode(cap)
    assert (len(data), data[2], data[3]) == (43, 12, 37)
    payload = data[4:-2]
    assert struct.unpack("<IBB8B8BBBfIBI", payload) == (
        (0xDEADBEEF, 0, 3) + cap.signal + cap.element + (3, 2, -1.5, 200, 4, 123456))
    values = tuple(0.25 * k - 3.0 for k in range(40))
    ans = CaptureData(id=7, op=4, status=0, state=3, channels=2, signal=(6, 7) + (0,) * 6, element=(1, 1) + (0,) * 6,
                      trigger=1, divider=1, depth=2048, pre=200, trigger_tick=4321, first_tick=4121, offset=80,
                      count=40, values=values)
    data = protocol.encode(ans)
    assert (len(data), data[2], data[3]) == (213, 13, 207)
    payload = data[4:-2]
    assert struct.unpack_from("<IBBBB", payload, 0) == (7, 4, 0, 3, 2)
    assert struct.unpack_from("<BBIIIIIB", payload, 24) == (1, 1, 2048, 200, 4321, 4121, 80, 40)
    assert struct.unpack_from("<40f", payload, 47) == values
    for frame in (cap, ans):
        (raw,) = Parser(protocol).feed(protocol.encode(frame))
        assert protocol.decode(raw.type, raw.payload) == frame
    assert {FrameType.CAPTURE, FrameType.CAPTURE_DATA} <= set(protocol.frames)


def test_the_declarations_capture(protocol: Protocol) -> None:
    spec = protocol.capture
    assert (spec.channels, spec.values, spec.chunk) == (8, 4096, 40)
    assert (spec.depth(1), spec.depth(3), spec.depth(8)) == (4096, 1365, 512)
    assert capture_signals_text(protocol) == VALID
    error, residual = spec.signal("error"), spec.signal("residual")
    assert error is not None and residual is not None and spec.signal("nosuch") is None
    assert [error.unit_of(k) for k in range(6)] == ["m", "m", "m", "rad", "rad", "rad"]
    assert (residual.code, residual.unit_of(5), residual.unit_of(6)) == (6, "N m", "")
    assert protocol.names(NameList.CAPTURE_OPS) == ["arm", "trigger", "abort", "status", "read"]
    assert protocol.names(NameList.CAPTURE_TRIGGERS) == ["manual", "fault", "command", "rising", "falling"]
    assert protocol.names(NameList.CAPTURE_STATES) == ["idle", "armed", "triggered", "done"]
    assert protocol.name_of(NameList.CAPTURE_STATUSES, 5) == "bad_span"


def test_a_declaration_without_the_capture_is_named(tmp_path: Path) -> None:
    d = json.loads(Path(PROTOCOL_JSON).read_text())
    del d["capture"]["statuses"]
    path = tmp_path / "p.json"
    path.write_text(json.dumps(d))
    with pytest.raises(ClientError, match="not a protocol description this client reads: KeyError"):
        Protocol(str(path))


# --------------------------------------------------------------------------- channels
@pytest.mark.parametrize("name, column, code, element", [
    ("residual[1]", "residual[1] [N m]", 6, 1),
    ("error[0]", "error[0] [m]", 0, 0),
    (" error[4] ", "error[4] [rad]", 0, 4),
    ("stage_cycles[3]", "stage_cycles[3] [cycles]", 10, 3),
    ("velocity[5]", "velocity[5] [rad/s]", 2, 5),
    ("codes[2]", "codes[2] [code]", 8, 2),
])
def test_channel_names(protocol: Protocol, name: str, column: str, code: int, element: int) -> None:
    c = parse_channel(protocol, name)
    assert (c.column, c.signal.code, c.element, c.name) == (column, code, element, name.strip())


@pytest.mark.parametrize("name, message", [
    ("speed[0]", f"no capture signal 'speed[0]': the signals are {VALID}"),
    ("residual[1", f"no capture signal 'residual[1': the signals are {VALID}"),
    ("residual[-1]", f"no capture signal 'residual[-1]': the signals are {VALID}"),
    ("residual", "capture signal residual: residual has 6 elements: name one, residual[0..5]"),
    ("residual[6]", "capture signal residual[6]: residual has 6 elements, residual[0..5]"),
    ("stage_cycles[8]", "capture signal stage_cycles[8]: stage_cycles has 8 elements, stage_cycles[0..7]"),
])
def test_bad_channel_names_are_named_errors(protocol: Protocol, name: str, message: str) -> None:
    with pytest.raises(ClientError) as e:
        parse_channel(protocol, name)
    assert str(e.value) == message


def test_a_signal_of_one_element_by_its_name_alone(tmp_path: Path) -> None:
    d = json.loads(Path(PROTOCOL_JSON).read_text())
    d["capture"]["signals"].append({"name": "load", "elements": 1, "unit": "%"})
    path = tmp_path / "p.json"
    path.write_text(json.dumps(d))
    p = Protocol(str(path))
    c = parse_channel(p, "load")
    assert (c.name, c.element, c.unit, c.signal.code) == ("load[0]", 0, "%", 11)
    assert parse_channel(p, "load[0]") == c
    assert capture_signals_text(p).endswith("stage_cycles[0..7], load")
    with pytest.raises(ClientError, match="load has 1 element, load"):
        parse_channel(p, "load[1]")


def test_channels_one_to_the_boards(protocol: Protocol) -> None:
    assert len(parse_channels(protocol, [("error", k) for k in range(6)] + ["tau[0]", "tau[1]"])) == 8
    with pytest.raises(ClientError, match="capture: 1 to 8 channels, not 9"):
        parse_channels(protocol, ["tau[0]"] * 9)
    with pytest.raises(ClientError, match="capture: 1 to 8 channels, not 0"):
        parse_channels(protocol, [])


# --------------------------------------------------------------------------- requests
def test_arm_sends_the_channels_trigger_and_span(protocol: Protocol) -> None:
    scope, board = scope_of(protocol, FakeCapture(protocol))
    a = scope.arm(["residual[1]", ("residual_threshold", 1), parse_channel(protocol, "error[0]")], "fault", pre=200,
                  divider=2)
    assert (scope.status_name(a), scope.state_name(a), a.channels, a.pre) == ("ok", "armed", 3, 200)
    (sent,) = board.captures()
    assert (sent.id, a.id) == (500, 500)
    assert sent.signal == (6, 7, 0, 0, 0, 0, 0, 0) and sent.element == (1, 1, 0, 0, 0, 0, 0, 0)
    assert (sent.channels, sent.trigger, sent.pre, sent.divider) == (3, 1, 200, 2)
    with pytest.raises(ClientError, match="capture trigger 'edge': one of manual, fault, command, rising, falling"):
        scope.arm(["tau[0]"], "edge")
    with pytest.raises(ClientError, match="capture divider 0: 1 to 255"):
        scope.arm(["tau[0]"], divider=0)
    assert len(board.captures()) == 1  # nothing sent for either


def test_the_read_loop_reads_every_value_in_chunks(protocol: Protocol) -> None:
    """Three channels: 1365 samples each, 4095 values, read 40 at a time from offset 0 (103 reads), split by
    channel; each sample's tick and time from the fault's tick."""
    capture = FakeCapture(protocol, fault_tick=5000)
    scope, board = scope_of(protocol, capture)
    scope.arm(["residual[1]", "residual_threshold[1]", "error[0]"], "fault", pre=200)
    with pytest.raises(CaptureRefused) as e:
        scope.read()  # not done yet
    assert (e.value.status, str(e.value)) == ("not_done", "capture read: refused: not_done")
    done = scope.wait_done(10)
    assert scope.state_name(done) == "done"
    result = scope.read()
    reads = [f for f in board.captures() if protocol.name_of(NameList.CAPTURE_OPS, f.op) == "read"]
    assert [f.offset for f in reads[1:]] == list(range(0, 4095, 40))
    assert (result.depth, result.pre, result.divider) == (1365, 200, 1)
    assert (result.trigger_tick, result.first_tick) == (5000, 4800)
    assert result.names == ["residual[1]", "residual_threshold[1]", "error[0]"]
    assert result.units == ["N m", "N m", "m"] and result.trigger == "fault"
    assert result.ticks == list(range(4800, 4800 + 1365))
    for c in range(3):
        assert list(result.values[c]) == [ramp(t, c) for t in result.ticks]
    t = result.times()
    assert (t[0], t[200], t[201], t[-1]) == (-0.2, 0.0, 0.001, 1.164)


def test_a_divider_spaces_the_samples(protocol: Protocol) -> None:
    capture = FakeCapture(protocol, fault_tick=3000, ticks_per_read=200)
    scope, _ = scope_of(protocol, capture)
    scope.arm(["tau[0]"] * 8, "fault", pre=100, divider=3)
    assert scope.state_name(scope.wait_done(10)) == "done"
    r = scope.read()
    # Samples at 1001, 1004, ...: the first at or after the fault's tick 3000 is 3002.
    assert (r.depth, r.pre, r.trigger_tick, r.first_tick) == (512, 100, 3002, 3002 - 300)
    assert r.ticks[:3] == [2702, 2705, 2708] and r.ticks[100] == 3002
    assert r.times()[99] == -0.003 and list(r.values[7][:2]) == [ramp(2702, 7), ramp(2705, 7)]


def test_an_early_trigger_holds_fewer_pre_samples(protocol: Protocol) -> None:
    capture = FakeCapture(protocol, fault_tick=1050)
    scope, _ = scope_of(protocol, capture)
    scope.arm(["tau[0]", "tau[1]"], "fault", pre=200)
    assert scope.state_name(scope.wait_done(10)) == "done"
    r = scope.read()
    assert (r.pre, r.trigger_tick, r.first_tick, r.depth) == (49, 1050, 1001, 49 + 1 + 2048 - 200 - 1)
    assert r.times()[49] == 0.0 and len(r.values[1]) == r.depth


def test_manual_trigger_abort_and_refusals(protocol: Protocol) -> None:
    capture = FakeCapture(protocol, fault_tick=None)
    scope, board = scope_of(protocol, capture)
    assert scope.status_name(scope.trigger()) == "not_armed"
    scope.arm(["codes[0]"], pre=10)
    scope.wait_ticks(11, 5)
    assert capture.tick - capture.armed_tick >= 11
    t = scope.trigger()
    assert (scope.ok(t), scope.state_name(t)) == (True, "armed")
    assert scope.state_name(scope.wait_done(10)) == "done"
    r = scope.read()
    assert r.pre == 10 and r.first_tick == r.trigger_tick - 10 and r.depth == 4096
    assert scope.state_name(scope.abort()) == "idle"
    assert op_names(protocol, board)[-1] == "abort"
    capture.refuse_arm = "bad_span"
    a = scope.arm(["codes[0]"], pre=5000)
    assert (scope.status_name(a), scope.state_name(a)) == ("bad_span", "idle")


def test_wait_done_gives_up_after_its_time(protocol: Protocol) -> None:
    scope, _ = scope_of(protocol, FakeCapture(protocol, fault_tick=None))
    scope.arm(["tau[0]"], "fault")
    a = scope.wait_done(0.2)
    assert scope.state_name(a) == "armed"


def test_no_answer_is_a_named_error(protocol: Protocol) -> None:
    scope, board = scope_of(protocol, None, timeout=0.2)
    with pytest.raises(ClientError, match=r"capture arm: no answer within 0\.2 s"):
        scope.arm(["tau[0]"])
    assert op_names(protocol, board) == ["arm"]


def test_a_capture_armed_again_while_read_is_named(protocol: Protocol) -> None:
    capture = FakeCapture(protocol, fault_tick=1500)
    scope, _ = scope_of(protocol, capture)
    scope.arm(["tau[0]"], "fault", pre=10)
    assert scope.state_name(scope.wait_done(10)) == "done"

    def rearmed(f: Capture) -> list[Frame]:
        if capture.reads == 3:
            capture.fault_tick = 1600  # another client's capture, done by now
        return capture(f)

    board = scope.client.transport
    assert isinstance(board, FakeBoard)
    board.capture_reply = rearmed
    with pytest.raises(ClientError, match="the capture changed while it was read"):
        scope.read()


def test_the_csv_of_a_result(protocol: Protocol) -> None:
    channels = tuple(parse_channels(protocol, ["residual[1]", "stage_cycles[2]"]))
    r = CaptureResult(channels, ((0.1, 0.2, 0.3), (10.0, 20.0, 30.0)), 3, 1, 2, 101, 99, "manual", 1000.0)
    out = io.StringIO()
    r.write_csv(out)
    assert out.getvalue() == ("tick,t [s],residual[1] [N m],stage_cycles[2] [cycles]\n"
                              "99,-0.002,0.1,10.0\n101,0.0,0.2,20.0\n103,0.002,0.3,30.0\n")
