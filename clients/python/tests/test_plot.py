"""Signals drawn (osc_client.plot, the verb plot): the PNG of --out from a stream of state frames, the figure's
axes and lines, the live view's window, named errors before the port is opened, matplotlib imported lazily."""
from __future__ import annotations

import itertools
import os
import struct
import subprocess
import sys
import time
from pathlib import Path

import matplotlib
import pytest

from osc_client import Protocol, Traces, cli, parse_signals
from osc_client.plot import TIME_LABEL, LivePlot, figure
from fakes import StateFeed
from test_record import FRAMES, VALID, endless, run, wire

SRC = str(Path(__file__).resolve().parent.parent / "src")
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def png_size(data: bytes) -> tuple[int, int]:
    """A PNG's width and height (its IHDR chunk, first after the signature)."""
    assert data[:8] == PNG_SIGNATURE and data[12:16] == b"IHDR"
    width, height = struct.unpack(">II", data[16:24])
    return int(width), int(height)


def test_plot_out_writes_a_png(protocol: Protocol, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "error.png"
    feed = StateFeed(protocol, endless(), 0.01)
    rc, opened = run(protocol, ["plot", "error", "x[1]", "x[3]", "error[1]", "--seconds", "0.3", "--out", str(out)],
                     feed)
    assert rc == 0 and opened == [feed] and feed.closed
    assert capsys.readouterr().out == f"{out}\n"
    data = out.read_bytes()
    assert len(data) > 1000 and data.startswith(PNG_SIGNATURE)
    assert png_size(data) == (900, 880)  # three axes (mm, m, rad): 9 x (1 + 3 x 2.6) inches at 100 dpi
    assert len(feed.sent) >= 1  # the link kept alive while recording


def test_the_figure_has_an_axes_per_unit_and_a_line_per_signal(protocol: Protocol) -> None:
    traces = Traces(protocol, parse_signals(protocol, ["error", "x[1]", "error[1]", "queued", "x[4]"]))
    for s in FRAMES:
        traces.add(wire(protocol, s))
    axes = figure(traces).get_axes()
    assert [ax.get_ylabel() for ax in axes] == ["position error [mm]", "position [m]", "value (code, count)",
                                                "angle [rad]"]
    assert [[line.get_label() for line in ax.get_lines()] for ax in axes] == [
        ["error", "error[1]"], ["x[1]"], ["queued"], ["x[4]"]]
    assert axes[-1].get_xlabel() == TIME_LABEL and "[s]" in TIME_LABEL
    (x1,) = axes[1].get_lines()
    assert list(x1.get_xdata()) == [1.0, 1.02, 1.04]
    assert list(x1.get_ydata()) == pytest.approx([0.15, 0.157, 0.168], abs=1e-7)
    error = axes[0].get_lines()[0]
    assert list(error.get_ydata()) == pytest.approx([0.0, 5.0, (2.0 ** 2 + 1.0 ** 2) ** 0.5], abs=1e-4)


def test_the_live_view_shows_the_last_window(protocol: Protocol) -> None:
    """The live view's lines and time axis: the window's last seconds (drawn here with Agg, no window)."""
    matplotlib.use("Agg")
    traces = Traces(protocol, parse_signals(protocol, ["error", "x[0]"]), keep=2.0)
    view = LivePlot(traces, 2.0, allow_non_gui=True)
    try:
        for s in itertools.islice(endless(), 251):  # 5 s of frames
            traces.add(s)
        view.update()
        assert view.axes[0].get_xlim() == pytest.approx((3.0, 5.0))
        xdata = list(view.lines[0].get_xdata())
        assert xdata[0] == pytest.approx(3.0) and xdata[-1] == pytest.approx(5.0) and len(xdata) == 101
        low, high = view.axes[0].get_ylim()
        assert low <= 3.0 <= high  # the error, 3 mm, in view
        assert view.is_open()
    finally:
        view.close()
    assert not view.is_open()


def test_out_without_seconds_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "e.png"
    with pytest.raises(SystemExit) as e:
        cli.main(["--port", "/dev/null", "plot", "error", "--out", str(out)])
    assert e.value.code == 2 and not out.exists()
    assert "plot --out: --seconds S is required" in capsys.readouterr().err


@pytest.mark.parametrize("signal, message", [
    ("speed", f"no signal 'speed': {VALID}"),
    ("x[9]", "signal x[9]: x has 6 elements, x[0..5]"),
])
def test_a_bad_signal_exits_2_before_anything_is_opened(protocol: Protocol, tmp_path: Path, signal: str, message: str,
                                                        capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "e.png"
    rc, opened = run(protocol, ["plot", "error", signal, "--seconds", "0.2", "--out", str(out)],
                     StateFeed(protocol, endless()))
    assert rc == 2 and opened == [] and not out.exists()
    assert capsys.readouterr().err == f"osc_client: {message}\n"


def test_an_out_that_cannot_be_written_exits_2(protocol: Protocol, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "none" / "e.png"
    rc, opened = run(protocol, ["plot", "error", "--seconds", "0.2", "--out", str(out)], StateFeed(protocol, endless()))
    assert rc == 2 and opened == []
    assert capsys.readouterr().err == f"osc_client: plot --out {out}: cannot be written: No such file or directory\n"


def test_no_state_frame_leaves_no_png(protocol: Protocol, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "e.png"
    rc, opened = run(protocol, ["plot", "error", "--seconds", "0.2", "--out", str(out)], StateFeed(protocol, iter(())))
    assert rc == 1 and len(opened) == 1 and not out.exists()
    captured = capsys.readouterr()
    assert captured.out == "" and "no state frame within the time" in captured.err


def test_live_without_a_display_is_refused(protocol: Protocol, capsys: pytest.CaptureFixture[str]) -> None:
    matplotlib.use("Agg")  # as on a machine without a display
    rc, opened = run(protocol, ["plot", "error"], StateFeed(protocol, endless()))
    assert rc == 2 and opened == []
    assert "no window can open (matplotlib's backend is agg" in capsys.readouterr().err


class SteppedClock:
    """The time module with a monotonic() that steps by `step` at each reading."""

    def __init__(self, step: float) -> None:
        self.t = 0.0
        self.step = step

    def monotonic(self) -> float:
        self.t += self.step
        return self.t

    def __getattr__(self, name: str) -> object:
        return getattr(time, name)


def test_the_live_loop_reads_draws_and_closes(protocol: Protocol, monkeypatch: pytest.MonkeyPatch) -> None:
    """plot without --out: the frames read between redraws, the window's last W seconds kept, the window closed
    after --seconds (drawn with Agg here: the view's window check let through)."""
    matplotlib.use("Agg")
    views: list[LivePlot] = []
    updates: list[int] = []

    class Drawn(LivePlot):
        def __init__(self, traces: Traces, window: float) -> None:
            super().__init__(traces, window, allow_non_gui=True)
            views.append(self)

        def update(self) -> None:
            super().update()
            updates.append(self.traces.frames)

    monkeypatch.setattr(cli, "LivePlot", Drawn)
    # cli's clock advances 0.05 s a reading: the loop's count of redraws does not hang on how fast a loaded machine
    # draws (the reads between them still wait for the feed's frames in real time).
    monkeypatch.setattr(cli, "time", SteppedClock(0.05))
    feed = StateFeed(protocol, endless(), 0.005)
    rc, opened = run(protocol, ["plot", "error", "x[1]", "--window", "0.5", "--seconds", "0.6"], feed)
    assert rc == 0 and opened == [feed] and feed.closed
    (view,) = views
    assert not view.is_open()  # closed at the end
    assert len(updates) >= 3 and updates == sorted(updates) and updates[-1] > updates[0] > 0
    t = list(view.lines[0].get_xdata())
    assert t[-1] - t[0] <= 0.5 and t == sorted(t) and view.traces.frames > len(t)


def test_matplotlib_is_imported_by_plot_only(tmp_path: Path) -> None:
    """The package, its command line and osc_client.plot import no matplotlib: it is needed to draw only."""
    code = ("import sys, osc_client, osc_client.cli, osc_client.plot, osc_client.record\n"
            "assert 'matplotlib' not in sys.modules, 'imported'\n"
            "print(osc_client.cli.main(['--port', '/dev/null', 'plot', 'nosuch']))\n"
            "assert 'matplotlib' not in sys.modules, 'imported for a bad signal'\n")
    run_ = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=dict(os.environ, PYTHONPATH=SRC),
                          capture_output=True, text=True, check=False)
    assert (run_.returncode, run_.stdout) == (0, "2\n"), run_.stderr
    assert "no signal 'nosuch'" in run_.stderr
