"""State frames as CSV (osc_client.record, the verb record) and the signals of plot: columns, rows, values,
the recording's end (--seconds, SIGINT, SIGTERM), named errors."""
from __future__ import annotations

import csv
import itertools
import math
import os
import signal
import struct
import time
from pathlib import Path
from typing import Iterator

import pytest

from osc_client import (Client, ClientError, CsvRecorder, NameList, Protocol, SignalKind, State, Traces, csv_header,
                        csv_row, parse_signal, parse_signals, signal_names, state_columns)
from osc_client import cli
from osc_client.record import f32_text
from fakes import StateFeed

HEADER = ("tick,t,state,stop,faults,queued,running_id,dropped,"
          "x_d[0],x_d[1],x_d[2],x_d[3],x_d[4],x_d[5],x[0],x[1],x[2],x[3],x[4],x[5],"
          "link[0],link[1],link[2],link[3],link[4],link[5],link[6],friction_checked,friction_stale")
FRAMES = (
    State(state=1, x_d=(0.4318, 0.15, 0.4, 0.0, 1.5, -0.25), x=(0.4318, 0.15, 0.4, 0.0, 1.5, -0.25), tick=1000),
    State(state=2, queued=1, running_id=7, x_d=(0.4318, 0.16, 0.4, 0.0, 1.5, -0.25),
          x=(0.4318, 0.157, 0.404, 0.0, 1.5, -0.25), tick=1020, link=(1, 0, 0, 3, 0, 0, 0)),
    State(state=2, stop=1, faults=1 << 5, running_id=7, dropped=2, x_d=(0.4318, 0.17, 0.4, 0.0, 1.5, -0.25),
          x=(0.4318, 0.168, 0.401, 0.0, 1.5, -0.25), tick=1040, link=(1, 0, 0, 3, 0, 0, 2), friction_checked=3,
          friction_stale=2),
)
"""Three state frames of a board: holding, then moving (one queued, a link error), then a fault latched."""
CSV = HEADER + "\n" + "".join(row + "\n" for row in (
    "1000,1.0,1,0,0,0,0,0,0.4318,0.15,0.4,0.0,1.5,-0.25,0.4318,0.15,0.4,0.0,1.5,-0.25,0,0,0,0,0,0,0,0,0",
    "1020,1.02,2,0,0,1,7,0,0.4318,0.16,0.4,0.0,1.5,-0.25,0.4318,0.157,0.404,0.0,1.5,-0.25,1,0,0,3,0,0,0,0,0",
    "1040,1.04,2,1,32,0,7,2,0.4318,0.17,0.4,0.0,1.5,-0.25,0.4318,0.168,0.401,0.0,1.5,-0.25,1,0,0,3,0,0,2,3,2"))
"""What record writes of FRAMES, as they come over the wire (32-bit floats)."""


def wire(p: Protocol, s: State) -> State:
    """The frame as a board sends it: its floats 32-bit."""
    spec = p.frames[s.TYPE]
    frame = p.decode(s.TYPE, p.encode(s)[4:-2])
    assert len(p.encode(s)) == spec.payload + 6 and isinstance(frame, State)
    return frame


def endless(first_tick: int = 0) -> Iterator[State]:
    """A board's frames for ever: every 20 ticks, the reference 3 mm ahead of the arm along y."""
    for k in itertools.count():
        yield State(state=1, x_d=(0.4, 0.103, 0.3, 0.0, 0.0, 0.0), x=(0.4, 0.1, 0.3, 0.0, 0.0, 0.0),
                    tick=first_tick + 20 * k)


def run(p: Protocol, argv: list[str], feed: StateFeed) -> tuple[int, list[StateFeed]]:
    """The command line over the feed; the transports it opened (none: the port was never touched)."""
    opened: list[StateFeed] = []

    def connect(port: str, baud: int, protocol: Protocol, keepalive: float) -> Client:
        opened.append(feed)
        return Client(feed, protocol=protocol, keepalive=keepalive)

    return cli.main(["--port", "/dev/fake"] + argv, connect=connect), opened


# --------------------------------------------------------------------------- columns and rows
def test_the_columns_are_the_state_frames_fields(protocol: Protocol) -> None:
    assert ",".join(csv_header(protocol)) == HEADER
    columns = {c.name: c for c in state_columns(protocol)}
    assert (columns["t"].unit, columns["t"].divisor) == ("s", protocol.control_hz) and protocol.control_hz == 1000
    assert [columns[f"x[{k}]"].unit for k in range(6)] == ["m", "m", "m", "rad", "rad", "rad"]
    assert (columns["x_d[4]"].field, columns["x_d[4]"].index, columns["x_d[4]"].type) == ("x_d", 4, "f32")
    assert (columns["faults"].unit, columns["link[6]"].index) == ("", 6)


def test_a_row_of_a_frame_off_the_wire(protocol: Protocol) -> None:
    columns = state_columns(protocol)
    assert [",".join(csv_row(columns, wire(protocol, s))) for s in FRAMES] == CSV.splitlines()[1:]
    assert protocol.name_of(NameList.MOTION_STATES, 2) == "moving" and protocol.fault_names(32) == "link_lost"


def test_a_keep_alive_reads_zeros(protocol: Protocol) -> None:
    """A frame whose vectors are empty (as a client's keep-alive) has a row of zeros, not an error."""
    row = csv_row(state_columns(protocol), State(tick=20))
    assert row[:2] == ["20", "0.02"] and set(row[2:8] + row[20:]) == {"0"} and set(row[8:20]) == {"0"}


@pytest.mark.parametrize("value, text", [
    (0.4318, "0.4318"), (0.157, "0.157"), (0.5, "0.5"), (-0.25, "-0.25"), (1.0 / 3.0, "0.33333334"),
    (100.0, "100.0"), (1e-7, "1e-07"), (0.0, "0.0"), (-0.0, "-0.0"), (math.inf, "inf"), (math.nan, "nan")])
def test_f32_text_is_the_shortest_that_reads_back(value: float, text: str) -> None:
    f32 = struct.unpack("<f", struct.pack("<f", value))[0]
    assert f32_text(f32) == text
    assert math.isnan(f32) or struct.unpack("<f", struct.pack("<f", float(text)))[0] == f32


def test_f32_text_of_a_value_no_float32_holds() -> None:
    assert f32_text(0.1) == "0.1" and f32_text(0.1 + 1e-12) == repr(0.1 + 1e-12)


def test_the_recorder_flushes_each_row(protocol: Protocol, tmp_path: Path) -> None:
    """A recording cut short is a file of whole rows: each is on the disk once written."""
    path = tmp_path / "r.csv"
    with open(path, "w", newline="") as f:
        recorder = CsvRecorder(protocol, f)
        assert path.read_text() == HEADER + "\n"
        recorder.write(wire(protocol, FRAMES[0]))
        recorder.write(wire(protocol, FRAMES[1]))
        assert path.read_text() == "".join(CSV.splitlines(keepends=True)[:3]) and recorder.rows == 2


# --------------------------------------------------------------------------- the verb record
def test_record_writes_a_row_per_state_frame(protocol: Protocol, tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "run.csv"
    feed = StateFeed(protocol, iter(FRAMES))
    rc, opened = run(protocol, ["record", str(path), "--seconds", "0.4"], feed)
    captured = capsys.readouterr()
    assert rc == 0 and opened == [feed] and feed.closed
    assert path.read_text() == CSV
    assert captured.out == "" and captured.err == f"record: 3 rows written to {path}\n"
    rows = list(csv.DictReader(path.open()))
    assert [r["x[1]"] for r in rows] == ["0.15", "0.157", "0.168"] and rows[2]["faults"] == "32"
    # The board's link kept alive while recording: all-zero state frames about every 0.1 s.
    assert len(feed.sent) >= 2 and set(feed.sent) == {wire(protocol, State())}


def test_record_to_standard_output(protocol: Protocol, capsys: pytest.CaptureFixture[str]) -> None:
    rc, _ = run(protocol, ["record", "-", "--seconds", "0.2"], StateFeed(protocol, iter(FRAMES)))
    captured = capsys.readouterr()
    assert rc == 0 and captured.out == CSV
    assert captured.err == "record: 3 rows written to standard output\n"


def test_seconds_end_an_endless_recording(protocol: Protocol, tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "run.csv"
    t0 = time.monotonic()
    rc, _ = run(protocol, ["record", str(path), "--seconds", "0.5"], StateFeed(protocol, endless(500), 0.02))
    elapsed = time.monotonic() - t0
    assert rc == 0 and elapsed >= 0.5  # not before its time (no upper bound: a loaded machine may be slow)
    rows = list(csv.DictReader(path.open()))
    assert 1 <= len(rows) <= 26  # a frame each 0.02 s at most
    assert [int(r["tick"]) for r in rows] == list(range(500, 500 + 20 * len(rows), 20))
    assert rows[-1]["t"] == repr((500 + 20 * (len(rows) - 1)) / 1000)
    assert capsys.readouterr().err == f"record: {len(rows)} rows written to {path}\n"


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_ends_the_recording_with_a_whole_file(protocol: Protocol, tmp_path: Path, signum: int,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    """No --seconds: SIGINT (Ctrl-C) or SIGTERM ends it, exit 0, every row written; the handlers put back."""
    before = signal.getsignal(signum)

    def frames() -> Iterator[State]:
        yield from FRAMES
        assert signal.getsignal(signum) not in (before, signal.SIG_DFL)  # record's own: it would not end us
        os.kill(os.getpid(), signum)

    path = tmp_path / "run.csv"
    rc, _ = run(protocol, ["record", str(path)], StateFeed(protocol, frames()))
    assert rc == 0
    assert path.read_text() == CSV
    assert capsys.readouterr().err == f"record: 3 rows written to {path}\n"
    assert signal.getsignal(signum) == before


@pytest.mark.parametrize("name, why", [("none/run.csv", "No such file or directory"), (".", "Is a directory")])
def test_a_file_that_cannot_be_written_exits_2(protocol: Protocol, tmp_path: Path, name: str, why: str,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    path = str(tmp_path / name)
    rc, opened = run(protocol, ["record", path, "--seconds", "0.2"], StateFeed(protocol, iter(FRAMES)))
    assert rc == 2 and opened == []  # the port never opened: nothing sent
    assert capsys.readouterr().err == f"osc_client: record: {path}: cannot be written: {why}\n"


def test_no_state_frame_exits_1_with_the_header(protocol: Protocol, tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "run.csv"
    rc, _ = run(protocol, ["record", str(path), "--seconds", "0.2"], StateFeed(protocol, iter(())))
    assert rc == 1 and path.read_text() == HEADER + "\n"
    assert capsys.readouterr().err == (f"record: 0 rows written to {path}\n"
                                       "osc_client: no state frame within the time (is a controller on the port?)\n")


@pytest.mark.parametrize("argv, message", [
    (["record"], "the following arguments are required: file"),
    (["record", "r.csv", "--seconds", "0"], "argument --seconds: 0: must be above 0"),
])
def test_record_bad_command_line_exits_2(argv: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as e:
        cli.main(["--port", "/dev/null"] + argv)
    assert e.value.code == 2 and message in capsys.readouterr().err


# --------------------------------------------------------------------------- signals
@pytest.mark.parametrize("name, signal_name, kind, field, index, unit", [
    ("x[0]", "x[0]", SignalKind.FIELD, "x", 0, "m"),
    ("x_d[2]", "x_d[2]", SignalKind.FIELD, "x_d", 2, "m"),
    (" x[05] ", "x[5]", SignalKind.FIELD, "x", 5, "rad"),
    ("queued", "queued", SignalKind.FIELD, "queued", None, ""),
    ("link[6]", "link[6]", SignalKind.FIELD, "link", 6, ""),
    ("error", "error", SignalKind.ERROR_NORM, "", None, "mm"),
    ("error[2]", "error[2]", SignalKind.ERROR, "", 2, "mm"),
])
def test_signal_names(protocol: Protocol, name: str, signal_name: str, kind: SignalKind, field: str,
                      index: int | None, unit: str) -> None:
    s = parse_signal(protocol, name)
    assert (s.name, s.kind, s.field, s.index, s.unit) == (signal_name, kind, field, index, unit)
    assert s.name in signal_names(protocol)


VALID = ("the signals are state, stop, faults, queued, running_id, dropped, x_d[0..5], x[0..5], tick, link[0..6], "
         "friction_checked, friction_stale, error, error[0..2]")


@pytest.mark.parametrize("name, message", [
    ("foo", f"no signal 'foo': {VALID}"),
    ("t", f"no signal 't': {VALID}"),
    ("x[-1]", f"no signal 'x[-1]': {VALID}"),
    ("x[1", f"no signal 'x[1': {VALID}"),
    ("x", "signal x: x has 6 elements: name one, x[0..5]"),
    ("x[6]", "signal x[6]: x has 6 elements, x[0..5]"),
    ("link[7]", "signal link[7]: link has 7 elements, link[0..6]"),
    ("queued[0]", "signal queued[0]: queued is a single number: queued, without an index"),
    ("error[3]", "signal error[3]: the position error has 3 axes, error[0..2] (x, y, z); error alone is its norm"),
])
def test_bad_signal_names_are_named_errors(protocol: Protocol, name: str, message: str) -> None:
    with pytest.raises(ClientError) as e:
        parse_signal(protocol, name)
    assert str(e.value) == message


def test_every_signal_name_parses(protocol: Protocol) -> None:
    names = signal_names(protocol)
    assert len(names) == 6 + 6 + 6 + 1 + 7 + 2 + 4 and names[-4:] == ["error", "error[0]", "error[1]", "error[2]"]
    assert [parse_signal(protocol, n).name for n in names] == names


def test_parse_signals_keeps_the_order_once_each(protocol: Protocol) -> None:
    assert [s.name for s in parse_signals(protocol, ["error", "x[1]", "error", "x[01]"])] == ["error", "x[1]"]


def test_the_error_signals(protocol: Protocol) -> None:
    """error[k] = x_d[k] - x[k] in mm; error = its norm over x, y, z (orientation not in it)."""
    s = State(x_d=(0.5, 0.25, 1.0, 0.3, 0.0, 0.0), x=(0.497, 0.254, 1.0, 0.0, 0.2, 0.0))
    values = [parse_signal(protocol, n).value(s) for n in ("error[0]", "error[1]", "error[2]", "error")]
    assert values == pytest.approx([3.0, -4.0, 0.0, 5.0], rel=1e-9, abs=1e-9)
    assert parse_signal(protocol, "x[1]").value(s) == 0.254 and parse_signal(protocol, "x_d[3]").value(s) == 0.3
    assert parse_signal(protocol, "error").value(wire(protocol, FRAMES[1])) == pytest.approx(5.0, abs=1e-4)
    assert parse_signal(protocol, "error").value(State()) == 0.0  # a keep-alive's empty vectors


def test_traces_keep_the_window(protocol: Protocol) -> None:
    signals = parse_signals(protocol, ["error[1]", "x[1]"])
    everything, window = Traces(protocol, signals), Traces(protocol, signals, keep=1.0)
    for s in itertools.islice(endless(), 151):  # ticks 0 .. 3000: 3 s
        everything.add(s)
        window.add(s)
    assert everything.frames == window.frames == 151 and len(everything.t) == 151
    assert list(window.t) == [k / 50 for k in range(100, 151)]  # t from 2.0 to 3.0 s
    assert len(window.values[0]) == len(window.values[1]) == 51
    assert list(window.values[0]) == pytest.approx([3.0] * 51, abs=1e-6)
    assert set(window.values[1]) == {0.1}
