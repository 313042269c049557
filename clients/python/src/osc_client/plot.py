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

A capture (``osc-client capture --out``: ``save_capture_png``) is drawn on axes at a fixed place in its
figure (``capture_axes_rects``), its channels against the time from the trigger, the trigger a vertical
line at t = 0 in TRIGGER_COLOUR, which no trace uses, and the time axis exactly the capture's span: the
trigger's pixel column is ``CAPTURE_LEFT_IN`` plus ``pre / (depth - 1)`` of the axes' width.
"""
from __future__ import annotations

from typing import IO, TYPE_CHECKING, Any, Sequence

from .errors import ClientError
from .record import Signal, Traces

if TYPE_CHECKING:
    from .capture import CaptureResult

NON_GUI_BACKENDS = frozenset({"agg", "cairo", "pdf", "pgf", "ps", "svg", "template"})
"""matplotlib's backends that open no window."""

UNIT_LABELS = {"m": "position [m]", "rad": "angle [rad]", "mm": "position error [mm]", "": "value (code, count)"}
"""The y axis' title of each unit's axes (another unit: ``[UNIT]``)."""

TIME_LABEL = "t [s] (the board's time: tick / control rate)"


def require_matplotlib(what: str = "plot") -> None:
    """A ClientError when matplotlib is missing (``what``: the verb or option that needs it)."""
    try:
        import matplotlib  # noqa: F401
    except ImportError as e:
        raise ClientError(f"{what} needs matplotlib (Debian: apt-get install python3-matplotlib)") from e


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


# --------------------------------------------------------------------------- a capture
CAPTURE_WIDTH_IN = 9.0
"""A capture figure's width [in]; its height: the margins and an axes per unit."""
CAPTURE_LEFT_IN, CAPTURE_RIGHT_IN = 1.0, 0.3
"""The axes' left and right margins [in]: the axes span the figure's width less them."""
CAPTURE_TOP_IN, CAPTURE_BOTTOM_IN = 0.75, 0.7
"""The margins above the first axes (the title, its legend) and below the last (the time axis' label) [in]."""
CAPTURE_AXES_IN, CAPTURE_GAP_IN = 2.3, 0.4
"""Each axes' height and the gap between two (the next one's legend) [in]."""
CAPTURE_DPI = 100
"""The PNG's pixels per inch."""
TRIGGER_COLOUR = "#ff0000"
"""The trigger's line (pure red: no trace's colour)."""
TRACE_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#17becf")
"""The channels' colours, in turn (matplotlib's tab10 without its red and olive)."""


def capture_figsize(axes: int) -> tuple[float, float]:
    """A capture figure's size [in] with ``axes`` axes."""
    return CAPTURE_WIDTH_IN, CAPTURE_TOP_IN + CAPTURE_BOTTOM_IN + axes * CAPTURE_AXES_IN + (axes - 1) * CAPTURE_GAP_IN


def capture_axes_rects(axes: int) -> list[tuple[float, float, float, float]]:
    """Each axes' place in the figure, the first at the top: (left, bottom, width, height), fractions of the
    figure's width and height (``Figure.add_axes``)."""
    w, h = capture_figsize(axes)
    left, width = CAPTURE_LEFT_IN / w, (w - CAPTURE_LEFT_IN - CAPTURE_RIGHT_IN) / w
    return [(left, (h - CAPTURE_TOP_IN - (k + 1) * CAPTURE_AXES_IN - k * CAPTURE_GAP_IN) / h, width,
             CAPTURE_AXES_IN / h) for k in range(axes)]


def channel_groups(units: Sequence[str]) -> list[tuple[str, list[int]]]:
    """The channels by unit, in the order of each unit's first channel: (unit, the channels' indices)."""
    groups: dict[str, list[int]] = {}
    for i, unit in enumerate(units):
        groups.setdefault(unit, []).append(i)
    return list(groups.items())


def capture_figure(result: CaptureResult) -> Any:
    """A capture drawn on a matplotlib Figure of the Agg backend: an axes per unit at ``capture_axes_rects``'
    places, each channel against the time from the trigger [s] in its colour (``TRACE_COLOURS``), the trigger a
    vertical line at t = 0 (``TRIGGER_COLOUR``), the time axis exactly the capture's span."""
    require_matplotlib("capture --out")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    groups = channel_groups(result.units)
    fig = Figure(figsize=capture_figsize(len(groups)), dpi=CAPTURE_DPI)
    FigureCanvasAgg(fig)
    t = result.times()
    span = (t[0], t[-1]) if t[-1] > t[0] else (t[0], t[0] + result.divider / result.control_hz)
    axes = [fig.add_axes(rect) for rect in capture_axes_rects(len(groups))]
    for ax, (unit, members) in zip(axes, groups):
        for i in members:
            ax.plot(t, list(result.values[i]), color=TRACE_COLOURS[i % len(TRACE_COLOURS)], linewidth=1.0,
                    label=result.names[i])
        ax.axvline(0.0, color=TRIGGER_COLOUR, linewidth=1.5, antialiased=False, zorder=5)
        ax.set_xlim(*span)
        ax.set_ylabel(unit_label(unit))
        ax.grid(True, alpha=0.3)
        # Above the axes, on the right (the y axis' offset text is on the left): no legend hides a trace or the
        # trigger's line.
        ax.legend(loc="lower right", bbox_to_anchor=(1.0, 1.0), ncol=len(members), fontsize="small", frameon=False,
                  borderaxespad=0.1)
        if ax is not axes[-1]:
            ax.tick_params(labelbottom=False)
    every = "every tick" if result.divider == 1 else f"every {result.divider} ticks"
    axes[-1].set_xlabel(f"t [s] from the trigger (tick {result.trigger_tick}; a sample {every})")
    fig.suptitle(f"capture: {result.depth} samples, trigger {result.trigger} at tick {result.trigger_tick} "
                 f"(red line), {result.pre} before it", y=1.0 - 0.2 / capture_figsize(len(groups))[1])
    return fig


def save_capture_png(result: CaptureResult, out: str | IO[bytes]) -> None:
    """Writes a capture's figure (``capture_figure``) as a PNG, a path or a binary file, at CAPTURE_DPI: the axes
    where ``capture_axes_rects`` says (no layout engine, no tight bounding box)."""
    capture_figure(result).savefig(out, format="png", dpi=CAPTURE_DPI)
