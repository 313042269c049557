"""osc-client: oscctl's verbs over the command protocol, the same lines printed, the same exit status.

    osc-client --port /dev/pts/7 state | enable | disable | clear | paper | stop | home | identify [--apply]
    osc-client --port /dev/pts/7 declare_pose start | zero | ready | stretch
    osc-client --port /dev/pts/7 move X Y Z [--rpy R P Y] [--relative] [--v V --a A --j J] [--replace] [--no-wait]
    osc-client --port /dev/pts/7 stream FILE.csv --rate HZ [--velocity] [--relative]
    osc-client --port /dev/pts/7 watch [--seconds S]
    osc-client --port /dev/pts/7 param list | get NAME | set NAME VALUE... | save | load | reset | check
    osc-client --port /dev/pts/7 record FILE.csv|- [--seconds S]
    osc-client --port /dev/pts/7 plot SIGNAL... [--window W] [--seconds S]
    osc-client --port /dev/pts/7 plot SIGNAL... --seconds S --out FILE.png
    osc-client --port /dev/pts/7 capture SIGNAL... [--trigger T] [--level-channel K --level X] [--pre N]
                                         [--divider D] [--wait S] [--csv FILE] [--out FILE.png]

record and plot are this program's own (oscctl has neither). record writes a CSV row per state frame
(tick, t [s], then the frame's fields, vectors by element: osc_client.record) until S seconds have
passed or SIGINT / SIGTERM (exit 0, the file whole; the rows counted on standard error). plot draws
signals of the state frames (x[0], x_d[2], queued, error[0..2], error: osc_client.record.parse_signal)
in a window over the last W seconds (default 10), or with --out into a PNG after S seconds (matplotlib,
imported by plot only). Either exits 1 when no state frame came.

capture runs the board's oscilloscope (osc_client.capture): arms it with the channels (``residual[1]``,
``error[0]``, ``stage_cycles[3]``: an element of a signal the board declares), a trigger (manual: this
program triggers it once the pre-trigger's samples are in), waits up to --wait seconds for it to be done
(else aborts it, exit 1), reads it, prints ``captured N samples x C channels, trigger tick T (pre P), first
tick F``, and writes it as CSV (--csv: tick, t [s] from the trigger, a column per channel) and a PNG (--out).
A refused request prints ``refused: STATUS`` (exit 1).

Exit status 0: accepted or done; 1: refused, aborted or timed out; 2: a bad command line, port or
file (``osc_client: MESSAGE`` on standard error). Also ``python3 -m osc_client``.
"""
from __future__ import annotations

import argparse
import contextlib
import math
import os
import signal
import sys
import time
from types import FrameType as PythonFrame
from typing import IO, Callable, Iterator, Sequence, TextIO

from .capture import DONE, MANUAL, WAITING, CaptureRefused, CaptureResult, Oscilloscope, parse_channels
from .client import Client, Outcome, Status
from .errors import ClientError
from .frames import CaptureData, FrameType, Identify, IdentifyPayload, ParamAnswer, State
from .paths import read_stream_csv, resample_path
from .plot import LivePlot, require_matplotlib, save_capture_png, save_png
from .protocol import NameList, Protocol, int_range
from .record import CsvRecorder, Signal, Traces, parse_signals
from .text import (DRIVES, answer_text, capture_text, identify_offset_text, identify_payload_text, identify_text,
                   margins_text, param_line, state_change_text, state_text)

Connect = Callable[[str, int, Protocol, float], Client]
"""Opens the client of a port: (port, baud, protocol, keepalive)."""
Open = Callable[[], Client]
"""Opens the command line's client (record and plot open it once their own files are open)."""

LEVEL_TRIGGERS = ("rising", "falling")
"""capture's triggers that compare a channel with a level (the protocol's names: checked by the tests)."""
SIMPLE_VERBS = ("state", "enable", "disable", "clear", "paper", "stop", "home")
PARAM_OPS = ("list", "get", "set", "save", "load", "reset", "check")
IDENTIFY_FRAME_WAIT = 10.0
"""Seconds identify waits for the estimate after the run's end (oscctl's kIdentifyFrameWaitS): the board solves it
after the end (38 million instructions: 0.25 s on the F407, seconds on a slow core or a loaded simulator) and sends it
at once; the wait ends when it comes."""


def report(o: Outcome) -> int:
    """Prints the outcome; its exit status."""
    print(o.text(), flush=True)
    return 0 if o.ok() else 1


def cmd_simple(c: Client, a: argparse.Namespace) -> int:
    """enable, disable, clear, paper, stop, home: the answer; for stop, disable and home the end too."""
    cid = c.command(a.verb)
    o = c.wait_answer(cid, a.timeout)
    rc = report(o)
    if o.status != Status.ACCEPTED or o.answer is None:
        return rc
    abort = c.protocol.name_of(NameList.REASONS, o.answer.abort)
    if abort != "none":  # the motion this command ended (stop, disable)
        print(f"aborted {o.answer.aborted_id}: {abort}", flush=True)
    if a.verb not in ("stop", "disable", "home"):
        return rc
    return report(c.wait_done(cid, a.timeout))


def cmd_declare_pose(c: Client, a: argparse.Namespace) -> int:
    return report(c.wait_answer(c.declare_pose(a.pose), a.timeout))


def cmd_move(c: Client, a: argparse.Namespace) -> int:
    rpy = [math.radians(x) for x in a.rpy] if a.rpy else None
    cid = c.move_to(a.xyz, rpy, a.relative, a.replace, c.limits(a.v, a.a, a.j))
    o = c.wait_answer(cid, a.timeout)
    print(f"{o.text()} (id {cid})", flush=True)
    if o.status != Status.ACCEPTED or a.no_wait:
        return 0 if o.ok() else 1
    return report(c.wait_done(cid, a.timeout))


def cmd_stream(c: Client, a: argparse.Namespace) -> int:
    rows, has_rpy = read_stream_csv(a.file)
    o = c.stream(resample_path(rows, a.rate), has_rpy, a.rate, a.relative, c.limits(a.v, a.a, a.j), a.timeout,
                 a.velocity)
    print(f"{o.text()} (id {o.id})", flush=True)
    if o.skipped:
        print(f"osc_client: warning: {o.skipped} setpoints skipped: this client fell behind the stream's schedule",
              file=sys.stderr)
    if o.status != Status.ACCEPTED:
        return 0 if o.ok() else 1
    return report(c.wait_done(o.id, a.timeout))


def cmd_state(c: Client, a: argparse.Namespace) -> int:
    s = c.state(min(a.timeout, 10.0))
    if s is None:
        print("osc_client: no state frame within the time (is a controller on the port?)", file=sys.stderr)
        return 1
    print(state_text(c.protocol, s), end="")
    return 0


def cmd_watch(c: Client, a: argparse.Namespace) -> int:
    """Every answer, and each state frame that changes the state, stop, faults, queue or running id."""
    last: list[tuple[int, ...]] = []

    def on_state(s: State) -> None:
        key = (s.state, s.stop, s.faults, s.queued, s.running_id)
        if last and last[0] == key:
            return
        print(state_change_text(c.protocol, s), flush=True)
        last[:] = [key]

    c.on_answer = lambda f: print(answer_text(c.protocol, f), flush=True)
    c.on_state = on_state
    try:
        c.pump(a.seconds if a.seconds else float("inf"))
    except KeyboardInterrupt:
        pass
    return 0


def param_refused(c: Client, r: ParamAnswer) -> int:
    """0 when ok, else 1 with the reason printed."""
    if r.status == 0:
        return 0
    print(f"refused: {c.protocol.name_of(NameList.PARAM_STATUSES, r.status)}")
    return 1


def check_param(ap: argparse.ArgumentParser, p: Protocol, a: argparse.Namespace) -> None:
    """The param command line's own checks, as oscctl's: a known name, as many values as elements."""
    if a.op not in ("get", "set"):
        if a.name is not None or a.values:
            ap.error(f"param {a.op} takes no name")
        return
    q = p.parameter(a.name)
    if q is None:
        ap.error(f"param {a.name}: no such parameter ({', '.join(x.name for x in p.parameters)})")
    n = q.count
    if a.element is not None and not 0 <= a.element < n:
        ap.error(f"param {a.name} --element {a.element}: it has {n} element" + ("s" if n > 1 else ""))
    if a.op == "get":
        if a.values:
            ap.error("param get takes no value")
        return
    want = 1 if a.element is not None else n
    if len(a.values) != want:
        ap.error(f"param set {a.name}: {want} value" + ("s" if want > 1 else "") + (
            " (one element)" if a.element is not None else " (one per element; --element E sets one)") +
            f", got {len(a.values)}")


def cmd_param(c: Client, a: argparse.Namespace) -> int:
    p = c.protocol
    if a.op in ("list", "get"):
        table = p.parameters if a.op == "list" else [q for q in p.parameters if q.name == a.name]
        only = a.element if a.op == "get" else None  # get --element E: that element alone
        for q in table:
            for e in range(q.count):
                if only is None or e == only:
                    r = c.param("get", q.index, e, timeout=a.timeout)
                    if param_refused(c, r):
                        return 1
                    print(param_line(p, q, r))
        return 0
    if a.op == "set":
        q = next(q for q in p.parameters if q.name == a.name)
        for k, v in enumerate(a.values):
            e = a.element if a.element is not None else k
            r = c.param("set", q.index, e, v, timeout=a.timeout)
            if param_refused(c, r):
                if r.margins[1] > 0:
                    print(margins_text(p, r))
                return 1
            print(param_line(p, q, r))
            if r.flags & p.param_flags["warn_37"]:
                print(margins_text(p, r))
        return 0
    r = c.param(a.op, timeout=a.timeout)
    if param_refused(c, r):
        return 1
    print(margins_text(p, r) if a.op == "check" else f"{a.op}: ok")
    return 0


def apply_identify_payload(c: Client, a: argparse.Namespace, f: IdentifyPayload) -> int:
    """identify --payload --apply: the payload's estimate into payload_mass, payload_com and payload_inertia (the
    torque off already), as oscctl's: the inertia zeroed first, then its moments before its products; where the
    parameters refuse it (not_physical, or a moment below 0 out_of_range: an estimate's noise about a point mass)
    it is zeroed again, products first, left so, and said. A mass within two of its standard deviations of 0 is no
    payload: all of it set to 0. Then payload_allowance goes back to 0: the payload is identified."""
    p = c.protocol

    def put(name: str, e: int, v: float, quiet: bool = False) -> int:
        q = p.parameter(name)
        if q is None:
            raise ClientError(f"identify --apply: this protocol has no parameter {name}")
        r = c.param("set", q.index, e, v, timeout=a.timeout)
        if quiet and p.name_of(NameList.PARAM_STATUSES, r.status) in ("not_physical", "out_of_range"):
            return -1
        if param_refused(c, r):
            return 1
        print(param_line(p, q, r))
        return 0
    none = not f.mass > 2 * f.pi_sd[0]
    keep = 0.0 if none else 1.0
    rc = put("payload_mass", 0, keep * f.mass)
    for k in range(3):
        rc = rc or put("payload_com", k, keep * f.com[k])
    for k in range(6):
        rc = rc or put("payload_inertia", k, 0.0)
    if none and rc == 0:
        print("payload: none found (its mass within 2 standard deviations of 0): set to none")
    for k in range(6):
        rc = rc or (0 if none else put("payload_inertia", k, f.inertia[k], quiet=True))
    if rc == -1:
        # Back in the reverse order: each zero returns to a tensor the board accepted on the way (a moment zeroed
        # before the products would leave a product beside a zero moment, which is not positive semidefinite).
        for k in reversed(range(6)):
            if put("payload_inertia", k, 0.0):
                return 1
        print("payload_inertia: refused (the estimate's noise about a point mass): left at 0")
        rc = 0
    return rc or put("payload_allowance", 0, 0.0)


def apply_identify(c: Client, a: argparse.Namespace, f: Identify, fp: IdentifyPayload | None = None) -> int:
    """identify --apply: the torque off (a disable), then the estimate's friction and armatures into friction_vis,
    friction_cou, friction_sti and armature_correction, each value within its element's range (an estimate below
    0 is set to 0), and the payload's estimate when given (apply_identify_payload). Each value set is printed;
    ``param save`` keeps them."""
    o = c.wait_done(c.disable(), a.timeout)
    if o.status != Status.DONE:
        return report(o)
    p = c.protocol
    n = DRIVES
    for name, values in (("friction_vis", f.friction[:n]), ("friction_cou", f.friction[n:2 * n]),
                         ("friction_sti", f.friction[2 * n:]), ("armature_correction", f.armature)):
        q = p.parameter(name)
        if q is None or q.count != len(values):
            raise ClientError(f"identify --apply: this protocol has no parameter {name} of {len(values)} elements")
        for e, v in enumerate(values):
            r = c.param("get", q.index, e, timeout=a.timeout)  # the element's range
            if param_refused(c, r):
                return 1
            v = r.lo if v < r.lo else r.hi if r.hi < v else v  # std::clamp's
            r = c.param("set", q.index, e, v, timeout=a.timeout)
            if param_refused(c, r):
                return 1
            print(param_line(p, q, r))
    if fp is not None:
        rc = apply_identify_payload(c, a, fp)
        if rc:
            return rc
    print("applied, the torque off: enable goes on from them; param save keeps them for the next power-on")
    return 0


def cmd_identify(c: Client, a: argparse.Namespace) -> int:
    """identify: the run's answer and end, then the board's estimate (its identify frame), and with --apply the
    estimate into the parameters. Exit 1 when the run was refused or aborted, its estimate failed, or --apply
    found none to apply."""
    cid = c.identify(payload=a.payload)
    o = c.wait_answer(cid, a.timeout)
    rc = report(o)
    if o.status != Status.ACCEPTED:
        return rc
    rc = report(c.wait_done(cid, a.timeout))
    f = c.wait_identify(cid, IDENTIFY_FRAME_WAIT)
    if f is None:
        print("no estimate: the board sent no identify frame (a firmware from before the boards estimated runs the "
              "motion alone; or the frame was lost)",
              flush=True)
        return 1 if a.apply else rc
    print(identify_text(c.protocol, f), end="", flush=True)
    fo = c.wait_identify_offset(cid, IDENTIFY_FRAME_WAIT)
    print(identify_offset_text(c.protocol, fo) if fo is not None
          else "no offset estimate: the board sent no identify_offset frame\n", end="", flush=True)
    fp = None
    if a.payload:
        fp = c.wait_identify_payload(cid, IDENTIFY_FRAME_WAIT)
        print(identify_payload_text(c.protocol, fp) if fp is not None
              else "no payload estimate: the board sent no identify_payload frame\n", end="", flush=True)
    if c.protocol.name_of(NameList.IDENTIFY_STATUSES, f.status) != "ok" or (a.payload and fp is None):
        return 1
    return apply_identify(c, a, f, fp) if a.apply else rc


@contextlib.contextmanager
def until_signal() -> Iterator[Callable[[], bool]]:
    """While in it, SIGINT and SIGTERM end a recording instead of the program: what it gives tells whether
    one came (give it as ``Client.pump``'s ``until``). Their handlers are put back after. Outside the main
    thread no handler can be set: a KeyboardInterrupt in it ends it then, quietly too."""
    came: list[int] = []

    def handler(signum: int, frame: PythonFrame | None) -> None:
        came.append(signum)

    kept: dict[signal.Signals, Callable[[int, PythonFrame | None], object] | int | None] = {}
    try:
        for sig in (signal.SIGINT, signal.SIGTERM):
            kept[sig] = signal.signal(sig, handler)
    except ValueError:  # not the main thread
        pass
    try:
        yield lambda: bool(came)
    except KeyboardInterrupt:
        pass
    finally:
        for sig, previous in kept.items():
            signal.signal(sig, previous)


def no_state_frame() -> int:
    print("osc_client: no state frame within the time (is a controller on the port?)", file=sys.stderr)
    return 1


def open_text(path: str, what: str) -> TextIO:
    """A text file opened for writing (CSV: no newline translation); a ClientError ``WHAT: cannot be written:
    why`` when it cannot be (``what`` names the verb and the file)."""
    try:
        return open(path, "w", newline="")
    except OSError as e:
        raise ClientError(f"{what}: cannot be written: {e.strerror or e}") from e


def open_binary(path: str, what: str) -> IO[bytes]:
    """A binary file (a PNG) opened for writing, as ``open_text``."""
    try:
        return open(path, "wb")
    except OSError as e:
        raise ClientError(f"{what}: cannot be written: {e.strerror or e}") from e


def cmd_record(a: argparse.Namespace, p: Protocol, open_: Open) -> int:
    """record: a CSV row per state frame until --seconds or a signal; the file opened before the port."""
    stdout = a.file == "-"
    where = "standard output" if stdout else a.file
    out = sys.stdout if stdout else open_text(a.file, f"record: {a.file}")
    recorder: CsvRecorder | None = None
    try:
        with until_signal() as stopped:
            recorder = CsvRecorder(p, out)
            c = open_()
            try:
                c.on_state = recorder.write
                c.pump(a.seconds or math.inf, stopped)
            finally:
                c.close()
    except BrokenPipeError:  # record - | head: the reader has gone, the recording ends
        with contextlib.suppress(OSError, ValueError):
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no error flushing it at exit
    except OSError as e:
        raise ClientError(f"record: {where}: {e.strerror or e}") from e
    finally:
        if not stdout:
            out.close()
        if recorder is not None:  # also after a named error (the port hung up): the file's rows are whole
            rows = f"{recorder.rows} row" + ("" if recorder.rows == 1 else "s")
            print(f"record: {rows} written to {where}", file=sys.stderr, flush=True)
    return 0 if recorder is not None and recorder.rows else no_state_frame()


def cmd_plot(a: argparse.Namespace, p: Protocol, open_: Open) -> int:
    """plot: the signals live in a window, or with --out into a PNG after --seconds; the signals checked, the
    window or the PNG file opened before the port."""
    signals = parse_signals(p, a.signals)
    require_matplotlib()
    if a.out:
        return plot_png(a, p, signals, open_)
    traces = Traces(p, signals, keep=a.window)
    view = LivePlot(traces, a.window)
    try:
        with until_signal() as stopped:
            c = open_()
            try:
                c.on_state = traces.add
                deadline = time.monotonic() + (a.seconds or math.inf)
                while view.is_open() and not stopped():
                    left = deadline - time.monotonic()
                    if left <= 0:
                        break
                    c.pump(min(left, LIVE_REDRAW), stopped)
                    view.update()
            finally:
                c.close()
    finally:
        view.close()
    return 0 if traces.frames else no_state_frame()


LIVE_REDRAW = 0.1
"""Seconds between redraws of the live view (the frames read, the link kept alive, between them)."""


def plot_png(a: argparse.Namespace, p: Protocol, signals: Sequence[Signal], open_: Open) -> int:
    """plot --out: the PNG file opened, the signals recorded for --seconds (or until a signal), then drawn."""
    traces = Traces(p, signals)
    png = open_binary(a.out, f"plot --out {a.out}")
    done = False
    try:
        with png:
            with until_signal() as stopped:
                c = open_()
                try:
                    c.on_state = traces.add
                    c.pump(a.seconds, stopped)
                finally:
                    c.close()
            if traces.frames:
                save_png(traces, png)
                done = True
    finally:
        if not done and os.path.isfile(a.out):
            with contextlib.suppress(OSError):
                os.remove(a.out)  # no figure: no file
    if not done:
        return no_state_frame()
    print(a.out, flush=True)
    return 0


def check_capture(p: Protocol, a: argparse.Namespace) -> None:
    """capture's command line against the protocol (a ClientError, exit 2, before anything is opened): the
    channels, the trigger's name, the level's channel, the divider within its field."""
    a.channels = parse_channels(p, a.signals)
    triggers = p.names(NameList.CAPTURE_TRIGGERS)
    if a.trigger not in triggers:
        raise ClientError(f"capture --trigger {a.trigger}: one of {', '.join(triggers)}")
    level = a.trigger in LEVEL_TRIGGERS
    if not level and (a.level is not None or a.level_channel is not None):
        raise ClientError(f"capture --level and --level-channel apply to --trigger {' or '.join(LEVEL_TRIGGERS)} "
                          f"only, not {a.trigger}")
    if level and a.level is None:
        raise ClientError(f"capture --trigger {a.trigger} needs --level")
    a.level = 0.0 if a.level is None else a.level
    a.level_channel = 0 if a.level_channel is None else a.level_channel
    if not 0 <= a.level_channel < len(a.channels):
        raise ClientError(f"capture --level-channel {a.level_channel}: a channel of the {len(a.channels)} given, "
                          f"0 to {len(a.channels) - 1}")
    if not math.isfinite(a.level):
        raise ClientError(f"capture --level {a.level}: a finite number")
    fields = {f.name: f for f in p.frames[FrameType.CAPTURE].fields}
    for name in ("divider", "pre"):
        lo, hi = int_range(fields[name].type)
        lo = max(lo, 1) if name == "divider" else lo
        if not lo <= getattr(a, name) <= hi:
            raise ClientError(f"capture --{name} {getattr(a, name)}: {lo} to {hi}")


def capture_refused(scope: Oscilloscope, a: CaptureData) -> bool:
    """Prints ``refused: STATUS`` for a refused request: True when it was."""
    if scope.ok(a):
        return False
    print(f"refused: {scope.status_name(a)}", flush=True)
    return True


def run_capture(c: Client, a: argparse.Namespace) -> CaptureResult | None:
    """Arms the capture, triggers it (manual), waits for it to be done, reads it: the capture, or None after a
    refusal or a capture not done within --wait (aborted), the line saying so printed."""
    scope = Oscilloscope(c, a.timeout)
    armed = scope.arm(a.channels, a.trigger, a.pre, a.divider, a.level_channel, a.level)
    if capture_refused(scope, armed):
        return None
    every = f", every {a.divider} ticks" if a.divider != 1 else ""
    print(f"armed: {', '.join(ch.name for ch in a.channels)}; trigger {a.trigger}, pre {a.pre}{every}", flush=True)
    deadline = time.monotonic() + a.wait
    if a.trigger == MANUAL:
        # The pre-trigger's samples first: pre samples a divider apart, one more for the tick the arm came in.
        scope.wait_ticks((a.pre + 1) * a.divider, a.wait)
        if capture_refused(scope, scope.trigger()):
            return None
    last = scope.wait_done(max(0.0, deadline - time.monotonic()))
    state = scope.state_name(last)
    if state in WAITING:
        scope.abort()
        print(f"not done within {a.wait:g} s: the capture {state} (aborted)", flush=True)
        return None
    if state != DONE:
        print(f"not done: the capture {state} (aborted or armed again by another client)", flush=True)
        return None
    return scope.read()


def cmd_capture(a: argparse.Namespace, p: Protocol, open_: Open) -> int:
    """capture: the command line checked and the files opened before the port; the capture run, read, printed
    and written (each file's path printed). A file is left only when written whole."""
    check_capture(p, a)
    if a.out:
        require_matplotlib("capture --out")
    paths = [path for path in (a.csv, a.out) if path]
    with contextlib.ExitStack() as files:
        written = False
        try:
            csv_file = files.enter_context(open_text(a.csv, f"capture: {a.csv}")) if a.csv else None
            png_file = files.enter_context(open_binary(a.out, f"capture: {a.out}")) if a.out else None
            c = open_()
            try:
                result = run_capture(c, a)
            except CaptureRefused as e:
                print(f"refused: {e.status}", flush=True)
                return 1
            finally:
                c.close()
            if result is None:
                return 1
            print(capture_text(result), flush=True)
            try:
                if csv_file is not None:
                    result.write_csv(csv_file)
                if png_file is not None:
                    save_capture_png(result, png_file)
            except OSError as e:
                raise ClientError(f"capture: {e.strerror or e}") from e
            written = True
        finally:
            if not written:
                files.close()
                for path in paths:
                    with contextlib.suppress(OSError):
                        os.remove(path)  # no capture: no file
    for path in paths:
        print(path, flush=True)
    return 0


OWN_FILE_VERBS: dict[str, Callable[[argparse.Namespace, Protocol, Open], int]] = {
    "record": cmd_record, "plot": cmd_plot, "capture": cmd_capture}
"""The verbs that open a file (or a window) of their own before the port."""

VERBS: dict[str, Callable[[Client, argparse.Namespace], int]] = {
    "state": cmd_state, "move": cmd_move, "stream": cmd_stream, "watch": cmd_watch, "param": cmd_param,
    "declare_pose": cmd_declare_pose, "identify": cmd_identify}


def positive(text: str) -> float:
    v = float(text)
    if not v > 0:
        raise argparse.ArgumentTypeError(f"{text}: must be above 0")
    return v


def keepalive_seconds(text: str) -> float:
    v = float(text)
    if not 0 <= v <= 0.4:
        raise argparse.ArgumentTypeError(f"{text}: must be from 0 (none) to 0.4 (below the board's 0.5 s timeout)")
    return v


def parser() -> argparse.ArgumentParser:
    """The command line."""
    ap = argparse.ArgumentParser(
        prog="osc-client", description="A client of the controller's command protocol (docs/protocol.md). Exit "
        "status 0: accepted or done; 1: refused, aborted or timed out; 2: a bad command line, port or file.")
    ap.add_argument("--port", required=True, help="the serial device or pseudo-terminal (e.g. /dev/pts/7)")
    ap.add_argument("--baud", type=int, default=115200, help="baud rate of a serial device (default 115200)")
    ap.add_argument("--protocol", metavar="FILE", help="the board's osc_protocol.json (default: $OSC_PROTOCOL, else "
                    "the default arm's, installed with the package); a build for another arm writes BUILD/clients/"
                    "osc_protocol.json")
    ap.add_argument("--timeout", type=positive, default=120.0, help="seconds to wait for an answer or an end")
    ap.add_argument("--keepalive", type=keepalive_seconds, default=Client.KEEPALIVE,
                    help="while waiting, a keep-alive frame after this many seconds without a frame sent (default "
                         "0.1; 0: none): a board with local encoders stops a motion after 0.5 s of link silence")
    sub = ap.add_subparsers(dest="verb", required=True, metavar="VERB")
    for v in SIMPLE_VERBS:
        sub.add_parser(v, help="print the state frame" if v == "state" else f"send {v}")
    ip = sub.add_parser("identify", help="send identify (the identification run: the excitation motion about the "
                        "held joint angles); waits for its end and prints the board's estimate")
    ip.add_argument("--apply", action="store_true", help="then the estimate's friction and armatures into the "
                    "parameters friction_vis, friction_cou, friction_sti and armature_correction (the torque off "
                    "first: a disable), with --payload the payload's into payload_mass, payload_com and "
                    "payload_inertia; param save keeps them")
    ip.add_argument("--payload", action="store_true", help="estimate the payload at the flange too: its mass, "
                    "centre of mass and inertia (all ten of its inertial parameters, with the arm's own model: the "
                    "whole payload, whatever is set)")
    dp = sub.add_parser("declare_pose", help="the arm stands at a named pose (torque off; the pots must agree)")
    dp.add_argument("pose", help="the pose's name (osc_protocol.json's poses: start, zero, ready, stretch)")

    def limits(p: argparse.ArgumentParser) -> None:
        p.add_argument("--v", type=positive, help="linear speed limit [m/s]")
        p.add_argument("--a", type=positive, help="linear acceleration limit [m/s^2]")
        p.add_argument("--j", type=positive, help="linear jerk limit [m/s^3]")
        p.add_argument("--relative", action="store_true", help="offsets from where the queue ends (or the stream "
                       "starts)")
    m = sub.add_parser("move", help="a jerk-limited move_to of the wrist centre; waits until done")
    m.add_argument("xyz", type=float, nargs=3, metavar="X/Y/Z", help="X Y Z [m], base frame")
    m.add_argument("--rpy", type=float, nargs=3, metavar=("R", "P", "Y"), help="roll pitch yaw [deg]")
    m.add_argument("--replace", action="store_true", help="re-target the running motion instead of queueing")
    m.add_argument("--no-wait", action="store_true", help="return once accepted")
    limits(m)
    s = sub.add_parser("stream", help="stream a CSV path (t, x, y, z[, roll, pitch, yaw] in s, m, deg)")
    s.add_argument("file")
    s.add_argument("--rate", type=positive, required=True, help="setpoints per second: 1000 / N, N from 1 to 100")
    s.add_argument("--velocity", action="store_true",
                   help="send each setpoint with the path's velocity (its slope between rows): no delay of one period")
    limits(s)
    w = sub.add_parser("watch", help="print state changes and every answer")
    w.add_argument("--seconds", type=positive, help="for this long (default: until interrupted)")
    r = sub.add_parser("record", help="write a CSV row per state frame: tick, t [s], the frame's fields (vectors "
                       "by element: x_d[0]..x_d[5], x[0]..x[5], link[0]..link[6])")
    r.add_argument("file", help="the CSV file to write ('-': standard output)")
    r.add_argument("--seconds", type=positive, help="for this long (default: until SIGINT or SIGTERM)")
    pl = sub.add_parser("plot", help="draw signals of the state frames live (matplotlib), or into a PNG (--out)")
    pl.add_argument("signals", nargs="+", metavar="SIGNAL", help="a field's element or a field (x[0], x_d[2], "
                    "queued ...; x, x_d: m, rad), error[0..2] (x_d[k] - x[k], mm) or error (the position error's "
                    "norm, mm)")
    pl.add_argument("--window", type=positive, default=10.0, help="the live view's last seconds of board time "
                    "(default 10)")
    pl.add_argument("--seconds", type=positive, help="for this long (default: until the window is closed or "
                    "SIGINT; required with --out)")
    pl.add_argument("--out", metavar="PNG", help="no window: record for --seconds, then write this PNG (every "
                    "value) and print its path")
    cp = sub.add_parser("capture", help="the board's oscilloscope: arm a capture of signals at the tick rate, wait "
                        "for its trigger, read it; print its ticks, write a CSV (--csv) and a PNG (--out)")
    cp.add_argument("signals", nargs="+", metavar="SIGNAL", help="a channel: an element of a signal the board "
                    "declares, NAME[K] (residual[1], error[0], stage_cycles[3]; docs/protocol.md, \"Capture\"); a "
                    "signal of one element by its name alone")
    cp.add_argument("--trigger", default=MANUAL, help="what ends the pre-trigger: a trigger the protocol declares "
                    "(docs/protocol.md, \"Capture\": a fault latched, a command accepted, --level-channel crossing "
                    f"--level ...); {MANUAL}, the default: this program triggers it once the pre-trigger is recorded")
    cp.add_argument("--level-channel", type=int, metavar="K", help="a level's trigger (rising, falling) only: "
                    "the channel compared with --level, 0 for the first SIGNAL given (default 0)")
    cp.add_argument("--level", type=float, metavar="X", help="a level's trigger (rising, falling; required "
                    "there) only: the level, in the channel's unit")
    cp.add_argument("--pre", type=int, default=0, metavar="N", help="samples kept before the trigger's, below the "
                    "samples per channel (the board's buffer / the channels) (default 0)")
    cp.add_argument("--divider", type=int, default=1, metavar="D", help="a sample every D ticks (default 1: every "
                    "tick)")
    cp.add_argument("--wait", type=positive, default=30.0, metavar="S", help="seconds to wait for the capture to "
                    "be done (default 30); then it is aborted, exit 1")
    cp.add_argument("--csv", metavar="FILE", help="write the capture as CSV: tick, t [s] from the trigger, a "
                    "column per channel (its name and unit)")
    cp.add_argument("--out", metavar="PNG", help="draw the capture into this PNG (matplotlib): the channels against "
                    "the time from the trigger, an axes per unit, the trigger a red line at t = 0")
    pm = sub.add_parser("param", help="the controller's parameters: list, get, set, save, load, reset, check")
    pm.add_argument("op", choices=PARAM_OPS)
    pm.add_argument("name", nargs="?", help="the parameter (get, set)")
    pm.add_argument("values", type=float, nargs="*", help="set: one value per element, or one with --element")
    pm.add_argument("--element", type=int, help="get, set: only this element of a vector parameter")
    return ap


def open_client(port: str, baud: int, protocol: Protocol, keepalive: float) -> Client:
    """The client of a serial device or pseudo-terminal."""
    return Client(port, baud, protocol=protocol, keepalive=keepalive)


def main(argv: Sequence[str] | None = None, connect: Connect = open_client) -> int:
    """Runs one verb; its exit status. A bad command line exits (SystemExit 2) from argparse.

    ``connect`` opens the client (the tests give one over a recorded byte stream).
    """
    ap = parser()
    # param's values may follow its options (set k --element 0 2500): numbers left over after a param
    # are its values.
    a, extra = ap.parse_known_args(sys.argv[1:] if argv is None else list(argv))
    if extra and a.verb == "param":
        try:
            a.values += [float(x) for x in extra]
            extra = []
        except ValueError:
            pass
    if extra:
        ap.error("unrecognized arguments: " + " ".join(extra))
    if a.verb == "move" and not all(math.isfinite(x) for x in a.xyz + (a.rpy or [])):
        ap.error("move: X Y Z and --rpy must be finite numbers")
    if not 50 <= a.baud <= 4000000:
        ap.error(f"--baud {a.baud}: 50 to 4000000")
    if a.verb == "plot" and a.out is not None and a.seconds is None:
        ap.error("plot --out: --seconds S is required (how long to record before drawing)")
    try:
        if a.verb == "stream":
            read_stream_csv(a.file)  # a bad file before the port is touched
        protocol = Protocol(a.protocol)
        if a.verb == "param":
            check_param(ap, protocol, a)
        if a.verb in OWN_FILE_VERBS:
            return OWN_FILE_VERBS[a.verb](a, protocol, lambda: connect(a.port, a.baud, protocol, a.keepalive))
        c = connect(a.port, a.baud, protocol, a.keepalive)
        try:
            return VERBS.get(a.verb, cmd_simple)(c, a)
        finally:
            c.close()
    except ClientError as e:
        print(f"osc_client: {e}", file=sys.stderr)
        return 2
