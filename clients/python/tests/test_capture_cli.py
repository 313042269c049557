"""The command line's capture against a board's capture in memory (fakes.FakeCapture): its lines and exit
status, the CSV, the PNG's trigger line where the capture's span puts it, refusals, a capture not done in time
(aborted), named errors before the port is opened."""
from __future__ import annotations

import csv
import os
import re
import subprocess
import sys
from pathlib import Path

import matplotlib.image
import pytest

from fakes import FakeBoard, FakeCapture, ramp
from osc_client import Client, NameList, Protocol, cli
from osc_client.plot import CAPTURE_DPI, CAPTURE_LEFT_IN, CAPTURE_RIGHT_IN, CAPTURE_WIDTH_IN, TRIGGER_COLOUR

SRC = str(Path(__file__).resolve().parent.parent / "src")


def run(p: Protocol, argv: list[str], capture: FakeCapture | None,
        timeout: float = 5.0) -> tuple[int, FakeBoard | None]:
    """The command line over a FakeBoard with the capture (None: a board that answers no capture frame); the
    board, None when the port was never opened."""
    board = FakeBoard(p, lambda c: [], capture_reply=capture, on_read=capture.clock if capture else None)
    opened: list[FakeBoard] = []

    def connect(port: str, baud: int, protocol: Protocol, keepalive: float) -> Client:
        opened.append(board)
        return Client(board, protocol=protocol, keepalive=keepalive, first_id=300)

    rc = cli.main(["--port", "/dev/fake", "--timeout", f"{timeout:g}", "capture"] + argv, connect=connect)
    return rc, (opened[0] if opened else None)


def ops(p: Protocol, board: FakeBoard | None) -> list[str]:
    assert board is not None
    return [p.name_of(NameList.CAPTURE_OPS, f.op) for f in board.captures()]


def trigger_column(png: Path) -> tuple[float, int, int]:
    """The PNG's trigger line: the mean column of the pure red pixels of the columns that hold most of them (a
    vertical line's), its pixel count there, and the image's width."""
    image = matplotlib.image.imread(str(png))
    rgb = image[:, :, :3]
    red = (rgb[:, :, 0] > 0.99) & (rgb[:, :, 1] < 0.01) & (rgb[:, :, 2] < 0.01)
    counts = red.sum(axis=0)
    columns = [x for x, n in enumerate(counts) if n >= 0.5 * counts.max()]
    assert columns and max(columns) - min(columns) <= 4, columns  # one line, a few pixels wide
    return sum(columns) / len(columns), int(counts.max()), int(image.shape[1])


def expected_column(pre: int, depth: int) -> float:
    """Where the trigger's line must be: pre / (depth - 1) of the way across the axes, whose place in the figure
    is fixed (osc_client.plot's CAPTURE_* margins)."""
    left = CAPTURE_LEFT_IN * CAPTURE_DPI
    right = (CAPTURE_WIDTH_IN - CAPTURE_RIGHT_IN) * CAPTURE_DPI
    return left + (right - left) * pre / (depth - 1)


def test_a_fault_capture_printed_and_written(protocol: Protocol, tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    table, png = tmp_path / "r.csv", tmp_path / "r.png"
    rc, board = run(protocol, ["residual[1]", "residual_threshold[1]", "error[0]", "--trigger", "fault", "--pre",
                               "200", "--csv", str(table), "--out", str(png)], FakeCapture(protocol, fault_tick=5000))
    assert capsys.readouterr().out == (
        "armed: residual[1], residual_threshold[1], error[0]; trigger fault, pre 200\n"
        "captured 1365 samples x 3 channels, trigger tick 5000 (pre 200), first tick 4800\n"
        f"{table}\n{png}\n")
    assert rc == 0
    names = ops(protocol, board)
    assert names[0] == "arm" and "trigger" not in names and "abort" not in names
    assert names.count("read") == 103 and names[-103:] == ["read"] * 103

    rows = list(csv.reader(table.read_text().splitlines()))
    assert rows[0] == ["tick", "t [s]", "residual[1] [N m]", "residual_threshold[1] [N m]", "error[0] [m]"]
    body = rows[1:]
    assert len(body) == 1365
    assert body[200][:2] == ["5000", "0.0"] and [r[1] for r in body].index("0.0") == 200
    assert body[0][:2] == ["4800", "-0.2"] and body[-1][:2] == ["6164", "1.164"]
    assert all(int(r[0]) == 4800 + s for s, r in enumerate(body))
    assert all([float(v) for v in r[2:]] == [ramp(4800 + s, c) for c in range(3)] for s, r in enumerate(body))

    column, height, width = trigger_column(png)
    assert width == CAPTURE_WIDTH_IN * CAPTURE_DPI
    assert abs(column - expected_column(200, 1365)) <= 2, (column, expected_column(200, 1365))
    assert height > 100  # the line spans the axes (two: N m, m)


@pytest.mark.parametrize("pre, channels", [(0, ["tau[0]"]), (1000, ["tau[0]", "tau[1]"]), (511, ["codes[0]"] * 8)])
def test_the_trigger_line_follows_pre(protocol: Protocol, tmp_path: Path, pre: int, channels: list[str],
                                      capsys: pytest.CaptureFixture[str]) -> None:
    png = tmp_path / "c.png"
    rc, _ = run(protocol, channels + ["--trigger", "fault", "--pre", str(pre), "--out", str(png)],
                FakeCapture(protocol, fault_tick=1000 + 1 + pre, ticks_per_read=200))
    assert rc == 0
    depth = protocol.capture.depth(len(channels))
    assert f"captured {depth} samples x {len(channels)} channel" in capsys.readouterr().out
    column, _, _ = trigger_column(png)
    assert abs(column - expected_column(pre, depth)) <= 2, (column, expected_column(pre, depth))
    assert TRIGGER_COLOUR == "#ff0000"


def test_manual_triggers_once_the_pre_trigger_is_in(protocol: Protocol, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    capture = FakeCapture(protocol, fault_tick=None)
    table = tmp_path / "m.csv"
    rc, board = run(protocol, ["stage_cycles[3]", "--pre", "300", "--divider", "2", "--csv", str(table)], capture)
    out = capsys.readouterr().out.splitlines()
    assert rc == 0
    assert out[0] == "armed: stage_cycles[3]; trigger manual, pre 300, every 2 ticks"
    m = re.fullmatch(r"captured 4096 samples x 1 channel, trigger tick (\d+) \(pre 300\), first tick (\d+), "
                     r"every 2 ticks", out[1])
    assert m is not None, out[1]
    trigger, first = int(m.group(1)), int(m.group(2))
    assert first == trigger - 600 and first > capture.armed_tick  # the 300 samples before it recorded after the arm
    names = ops(protocol, board)
    assert names[:2] == ["arm", "trigger"]
    rows = list(csv.reader(table.read_text().splitlines()))
    assert rows[0] == ["tick", "t [s]", "stage_cycles[3] [cycles]"] and len(rows) == 4097
    assert rows[301][1] == "0.0" and rows[300][1] == "-0.002" and int(rows[2][0]) - int(rows[1][0]) == 2


def test_a_refused_arm_exits_1(protocol: Protocol, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    table, png = tmp_path / "r.csv", tmp_path / "r.png"
    rc, board = run(protocol, ["tau[0]", "--pre", "4096", "--csv", str(table), "--out", str(png)],
                    FakeCapture(protocol, refuse_arm="bad_span"))
    assert (rc, capsys.readouterr().out) == (1, "refused: bad_span\n")
    assert ops(protocol, board) == ["arm"]
    assert not table.exists() and not png.exists()  # no capture: no file


def test_a_capture_not_done_in_time_is_aborted(protocol: Protocol, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    table = tmp_path / "r.csv"
    rc, board = run(protocol, ["residual[0]", "--trigger", "fault", "--wait", "0.3", "--csv", str(table)],
                    FakeCapture(protocol, fault_tick=None))
    assert rc == 1
    assert capsys.readouterr().out == ("armed: residual[0]; trigger fault, pre 0\n"
                                       "not done within 0.3 s: the capture armed (aborted)\n")
    names = ops(protocol, board)
    assert names[0] == "arm" and names[-1] == "abort" and set(names[1:-1]) == {"status"}
    assert not table.exists()


def test_no_answer_exits_2(protocol: Protocol, capsys: pytest.CaptureFixture[str]) -> None:
    rc, board = run(protocol, ["tau[0]"], None, timeout=0.3)
    assert rc == 2 and ops(protocol, board) == ["arm"]
    assert capsys.readouterr().err == ("osc_client: capture arm: no answer within 0.3 s (a board without the "
                                       "capture, or a link that lost the frame)\n")


@pytest.mark.parametrize("argv, message", [
    (["speed[1]"], "no capture signal 'speed[1]': the signals are error[0..5], observer_error[0..5], "),
    (["tau[0]", "residual"], "capture signal residual: residual has 6 elements: name one, residual[0..5]"),
    (["tau[9]"], "capture signal tau[9]: tau has 6 elements, tau[0..5]"),
    (["tau[0]"] * 9, "capture: 1 to 8 channels, not 9"),
    (["tau[0]", "--trigger", "edge"], "capture --trigger edge: one of manual, fault, command, rising, falling"),
    (["tau[0]", "tau[1]", "--trigger", "rising", "--level", "1", "--level-channel", "2"],
     "capture --level-channel 2: a channel of the 2 given, 0 to 1"),
    (["tau[0]", "--trigger", "falling", "--level", "nan"], "capture --level nan: a finite number"),
    (["tau[0]", "--trigger", "rising"], "capture --trigger rising needs --level"),
    (["tau[0]", "--level", "1"], "capture --level and --level-channel apply to --trigger rising or falling only, "
     "not manual"),
    (["tau[0]", "--trigger", "fault", "--level-channel", "0"],
     "capture --level and --level-channel apply to --trigger rising or falling only, not fault"),
    (["tau[0]", "--divider", "0"], "capture --divider 0: 1 to 255"),
    (["tau[0]", "--divider", "256"], "capture --divider 256: 1 to 255"),
    (["tau[0]", "--pre", "-1"], "capture --pre -1: 0 to 4294967295"),
])
def test_a_bad_command_line_exits_2_before_the_port(protocol: Protocol, tmp_path: Path, argv: list[str],
                                                    message: str, capsys: pytest.CaptureFixture[str]) -> None:
    table = tmp_path / "r.csv"
    rc, board = run(protocol, argv + ["--csv", str(table)], FakeCapture(protocol))
    assert rc == 2 and board is None and not table.exists()
    err = capsys.readouterr().err
    assert err.startswith(f"osc_client: {message}") and err.count("\n") == 1


def test_a_file_that_cannot_be_written_exits_2(protocol: Protocol, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    png = tmp_path / "none" / "r.png"
    rc, board = run(protocol, ["tau[0]", "--out", str(png)], FakeCapture(protocol))
    assert rc == 2 and board is None
    assert capsys.readouterr().err == f"osc_client: capture: {png}: cannot be written: No such file or directory\n"


def test_capture_without_out_imports_no_matplotlib(tmp_path: Path) -> None:
    """The capture module and a capture's CSV need no matplotlib: --out alone imports it."""
    code = ("import sys, osc_client, osc_client.capture\n"
            "from osc_client import cli\n"
            "print(cli.main(['--port', '/dev/null', 'capture', 'nosuch[0]']))\n"
            "assert 'matplotlib' not in sys.modules, 'imported'\n")
    run_ = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=dict(os.environ, PYTHONPATH=SRC),
                          capture_output=True, text=True, check=False)
    assert (run_.returncode, run_.stdout) == (0, "2\n"), run_.stderr
    assert "no capture signal 'nosuch[0]'" in run_.stderr


def test_the_level_triggers_are_the_protocols(protocol: Protocol) -> None:
    """The CLI's level triggers (the ones --level applies to) are triggers the firmware declares."""
    from osc_client.cli import LEVEL_TRIGGERS
    from osc_client.protocol import NameList
    assert set(LEVEL_TRIGGERS) <= set(protocol.names(NameList.CAPTURE_TRIGGERS))
