"""Signals of the state frames drawn with matplotlib (``osc-client plot``): a PNG, or a live window.

matplotlib (Debian's ``python3-matplotlib``) is imported by these functions only, when called: the rest of
the package works without it. The figure has one axes per unit (signals in m, rad, mm, or codes and
counts), stacked over the board's time ``t`` [s], a labelled line per signal.

    from osc_client import Traces, parse_signals
    from osc_client.plot import save_png
    traces = Traces(c.protocol, parse_signals(c.protocol, ["error", "x[0]"]))
    c.on_state = traces.add
    c.pump(10)
    save_png(traces, "error.png")
"""
from __future__ import annotations

from typing import IO, Any

from .errors import ClientError
from .record import Signal, Traces

NON_GUI_BACKENDS = frozenset({"agg", "cairo", "pdf", "pgf", "ps", "svg", "template"})
"""matplotlib's backends that open no window."""

UNIT_LABELS = {"m": "position [m]", "rad": "angle [rad]", "mm": "position error [mm]", "": "value (code, count)"}
"""The y axis' title of each unit's axes (another unit: ``[UNIT]``)."""

TIME_LABEL = "t [s] (the board's time: tick / control rate)"


def require_matplotlib() -> None:
    """A ClientError when matplotlib is missing."""
    try:
        import matplotlib  # noqa: F401
    except ImportError as e:
        raise ClientError("plot needs matplotlib (Debian: apt-get install python3-matplotlib)") from e


def unit_groups(signals: tuple[Signal, ...]) -> list[tuple[str, list[int]]]:
    """The signals by unit, in the order of each unit's first signal: (unit, the signals' indices)."""
    groups: dict[str, list[int]] = {}
    for i, s in enumerate(signals):
        groups.setdefault(s.unit, []).append(i)
    return list(groups.items())


def unit_label(unit: str) -> str:
    """The y axis' title of the axes of a unit."""
    return UNIT_LABELS.get(unit, f"[{unit}]")


def draw(fig: Any, traces: Traces) -> tuple[list[Any], list[Any]]:
    """Lays the signals out on a matplotlib Figure: one axes per unit, a line per signal (labelled with its name,
    the data so far); the axes and the lines (in the signals' order)."""
    groups = unit_groups(traces.signals)
    axes = list(fig.subplots(len(groups), 1, sharex=True, squeeze=False)[:, 0])
    lines: list[Any] = [None] * len(traces.signals)
    t = list(traces.t)
    for ax, (unit, members) in zip(axes, groups):
        for i in members:
            (lines[i],) = ax.plot(t, list(traces.values[i]), label=traces.signals[i].name)
        ax.set_ylabel(unit_label(unit))
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper left", fontsize="small")
    axes[-1].set_xlabel(TIME_LABEL)
    fig.suptitle("state frames: " + ", ".join(s.name for s in traces.signals))
    return axes, lines


def figure(traces: Traces) -> Any:
    """The signals drawn on a matplotlib Figure of the Agg backend (no window, no pyplot)."""
    require_matplotlib()
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9.0, 1.0 + 2.6 * len(unit_groups(traces.signals))), layout="constrained")
    FigureCanvasAgg(fig)
    draw(fig, traces)
    return fig


def save_png(traces: Traces, out: str | IO[bytes]) -> None:
    """Writes the signals' figure as a PNG (a path or a binary file): every value of the traces."""
    figure(traces).savefig(out, format="png", dpi=100)


class LivePlot:
    """A window of pyplot's showing the last ``window`` seconds of the traces, redrawn by ``update``.

    A ClientError when no window can open (matplotlib's backend draws to files only: no display).
    """

    def __init__(self, traces: Traces, window: float, allow_non_gui: bool = False) -> None:
        require_matplotlib()
        import matplotlib.pyplot as plt

        backend = str(plt.get_backend()).lower()
        if backend in NON_GUI_BACKENDS and not allow_non_gui:
            raise ClientError(f"plot: no window can open (matplotlib's backend is {backend}: no display?); "
                              "--out PNG --seconds S draws to a file")
        self.traces, self.window = traces, window
        self._plt = plt
        self.fig = plt.figure(figsize=(9.0, 1.0 + 2.6 * len(unit_groups(traces.signals))), layout="constrained")
        self.axes, self.lines = draw(self.fig, traces)
        if backend not in NON_GUI_BACKENDS:
            plt.show(block=False)

    def is_open(self) -> bool:
        """The window is open (not closed by the user)."""
        return bool(self._plt.fignum_exists(self.fig.number))

    def update(self) -> None:
        """Redraws the lines with the traces' values, the time axis the last ``window`` seconds."""
        t = list(self.traces.t)
        for line, series in zip(self.lines, self.traces.values):
            line.set_data(t, list(series))
        if t:
            self.axes[0].set_xlim(max(t[0], t[-1] - self.window), max(t[-1], t[0] + 1e-3))
        for ax in self.axes:
            ax.relim()
            ax.autoscale_view(scalex=False)
        self.fig.canvas.draw_idle()
        self.fig.canvas.flush_events()

    def close(self) -> None:
        """Closes the window."""
        self._plt.close(self.fig)
