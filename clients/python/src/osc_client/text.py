"""Frames as oscctl prints them (the command line's output, which scripts and tests read)."""
from __future__ import annotations

import math
from typing import TYPE_CHECKING, Sequence

from .frames import Answer, Identify, IdentifyOffset, IdentifyPayload, ParamAnswer, State
from .protocol import NameList, Parameter, Protocol

if TYPE_CHECKING:
    from .capture import CaptureResult

IDENTIFIED_FRACTION = 0.025
"""A coefficient is identified when its standard deviation is within this fraction of it: the firmware's
params::kIdentifiedFraction (firmware/control/include/osc/control/params.hpp), which the protocol's JSON
does not carry."""

DRIVES = 6
"""The drives an identify frame reports (its armature count; friction holds three coefficients each)."""


def pose_text(x: Sequence[float]) -> str:
    """``0.4318 0.1500 0.4000 m, rpy 0.00 90.00 0.00 deg``: a pose of x, y, z [m], roll, pitch, yaw [rad]."""
    d = [math.degrees(v) for v in x[3:]]
    return f"{x[0]:.4f} {x[1]:.4f} {x[2]:.4f} m, rpy {d[0]:.2f} {d[1]:.2f} {d[2]:.2f} deg"


def state_text(p: Protocol, s: State) -> str:
    """The state frame, a line a field (the verb state)."""
    return (f"state: {p.name_of(NameList.MOTION_STATES, s.state)}\n"
            f"stop: {p.name_of(NameList.STOP_CATEGORIES, s.stop)}\n"
            f"faults: {p.fault_names(s.faults)}\n"
            f"queued: {s.queued}\n"
            f"running_id: {s.running_id}\n"
            f"reference: {pose_text(s.x_d)}\n"
            f"measured: {pose_text(s.x)}\n"
            f"dropped: {s.dropped}\n"
            f"tick: {s.tick}\n"
            f"friction_fit: {friction_fit_text(s.friction_checked, s.friction_stale)}\n")


def friction_fit_text(checked: int, stale: int) -> str:
    """``J1 fits, J2 stale, J3 -, ...``: each joint's friction as set, checked by the momentum law (fits, stale) or
    not yet (-): the state frame's friction_checked and friction_stale."""
    return ", ".join(f"J{i + 1} " + ("-" if not checked >> i & 1 else "stale" if stale >> i & 1 else "fits")
                     for i in range(DRIVES))


def state_change_text(p: Protocol, s: State) -> str:
    """A state frame in one line (the verb watch)."""
    return (f"tick {s.tick}: state {p.name_of(NameList.MOTION_STATES, s.state)}, "
            f"stop {p.name_of(NameList.STOP_CATEGORIES, s.stop)}, faults {p.fault_names(s.faults)}, "
            f"queued {s.queued}, running_id {s.running_id}")


def answer_text(p: Protocol, a: Answer) -> str:
    """An answer frame in one line (the verb watch): ``tick 812: move_to 17 accepted; state moving, queued 0``."""
    n = p.name_of
    text = f"tick {a.tick}:"
    if n(NameList.OUTCOMES, a.outcome) != "none":
        text += f" {n(NameList.VERBS, a.verb)} {a.id} {n(NameList.OUTCOMES, a.outcome)}"
        if n(NameList.OUTCOMES, a.outcome) == "refused":
            text += f": {n(NameList.REASONS, a.refusal)}"
        if a.cause:
            text += f" ({p.fault_names(a.cause)})"
        text += ";"
    if a.done_id:
        text += f" done {a.done_id};"
    if n(NameList.REASONS, a.abort) != "none":
        text += f" aborted {a.aborted_id}: {n(NameList.REASONS, a.abort)};"
    if n(NameList.COMPLETIONS, a.completion) != "none":
        text += f" completion {n(NameList.COMPLETIONS, a.completion)};"
    return text + f" state {n(NameList.MOTION_STATES, a.state)}, queued {a.queued}"


def param_line(p: Protocol, q: Parameter, a: ParamAnswer) -> str:
    """One element's line: ``ks[2] = 97 (0.001 to 1000; torque_off)``."""
    index = f"[{a.element}]" if q.count > 1 else ""
    unit = f" {q.unit}" if q.unit else ""
    off = "; torque_off" if a.flags & p.param_flags["torque_off"] else ""
    return f"{q.name}{index} = {a.value:.7g}{unit} ({a.lo:.7g} to {a.hi:.7g}{off})"


def margins_text(p: Protocol, a: ParamAnswer) -> str:
    """The gains' margins of a check (or of a gain refused as unstable), three lines."""
    warn = ": warning, the paper's sufficient condition cannot hold" if a.flags & p.param_flags["warn_37"] else ""
    m = a.margins
    return (f"observer margin {m[0]:.3g} (stable above 1: (4 - 2 k dt) / (b dt^2), b <= "
            f"{m[1]:.4g} 1/s^2 at the last pose)\n"
            f"loop margin {m[3]:.3g} (stable at 1 or above: the factor the gains may grow by at the last pose)\n"
            f"condition (37) {m[2]:.3g} (k_s k_nd / 2: above 1 it can hold){warn}")


def identify_text(p: Protocol, f: Identify) -> str:
    """An identify frame as oscctl prints it: the verdict, then (status ok) per drive each coefficient with its
    standard deviation, ``*`` where it is identified, and the armature correction."""
    text = ("identify %u: %s; %u samples, %u lost; condition %.3g; worst torque-prediction error %.1f %%\n"
            % (f.id, p.name_of(NameList.IDENTIFY_STATUSES, f.status), f.samples, f.lost, f.condition,
               100.0 * f.prediction_error))
    if p.name_of(NameList.IDENTIFY_STATUSES, f.status) != "ok":
        return text
    columns = ("viscous [N m s/rad]", "Coulomb [N m]", "Stribeck [N m]", "armature correction [kg m^2]")
    text += "drive  %-22s %-22s %-22s %s\n" % columns
    for i in range(DRIVES):
        text += "J%d    " % (i + 1)
        for c in range(3):  # viscous, Coulomb, Stribeck
            k = c * DRIVES + i
            text += " %9.4f +- %-7.4f%s" % (f.friction[k], f.friction_sd[k], "* " if f.identified >> k & 1 else "  ")
        text += " %9.4f +- %.4f\n" % (f.armature[i], f.armature_sd[i])
    return text + "(* identified: its standard deviation within %g %% of it)\n" % (100 * IDENTIFIED_FRACTION)


def identify_offset_text(p: Protocol, f: IdentifyOffset) -> str:
    """An identify_offset frame as oscctl prints it (status ok): each drive's torque offset with its standard
    deviation, on one line; "" otherwise."""
    if p.name_of(NameList.IDENTIFY_STATUSES, f.status) != "ok":
        return ""
    return ("torque offset [N m] (what each drive adds to the torque commanded; reported, not applied):"
            + "".join(" J%d %.4f +- %.4f" % (i + 1, f.offset[i], f.offset_sd[i]) for i in range(DRIVES)) + "\n")


def identify_payload_text(p: Protocol, f: IdentifyPayload) -> str:
    """An identify_payload frame as oscctl prints it (status ok): the mass, the centre of mass and the inertia about
    it, then the estimated parameters' standard deviations, ``*`` where identified; "" otherwise."""
    if p.name_of(NameList.IDENTIFY_STATUSES, f.status) != "ok":
        return ""

    def star(k: int) -> str:
        return "*" if f.identified >> k & 1 else ""
    text = ("payload: mass %.4f kg +- %.4f%s, centre of mass (%.2f, %.2f, %.2f) mm\n"
            % (f.mass, f.pi_sd[0], star(0), 1e3 * f.com[0], 1e3 * f.com[1], 1e3 * f.com[2]))
    text += "  inertia about it (Ixx Iyy Izz Ixy Ixz Iyz) [kg m^2]:" + "".join(" %.4g" % v for v in f.inertia) + "\n"
    text += "  standard deviations: m c [kg m]" + "".join(" %.2g%s" % (f.pi_sd[k], star(k)) for k in range(1, 4))
    text += "; inertia about frame 6's origin (Ixx Ixy Ixz Iyy Iyz Izz) [kg m^2]"
    return text + "".join(" %.2g%s" % (f.pi_sd[k], star(k)) for k in range(4, 10)) + "\n"


def capture_text(r: CaptureResult) -> str:
    """A capture read, in one line: ``captured 1024 samples x 2 channels, trigger tick 4321 (pre 200), first tick
    4121`` (and ``, every D ticks`` when it sampled less often than every tick)."""
    every = f", every {r.divider} ticks" if r.divider != 1 else ""
    return (f"captured {r.depth} samples x {len(r.channels)} channel" + ("s" if len(r.channels) != 1 else "") +
            f", trigger tick {r.trigger_tick} (pre {r.pre}), first tick {r.first_tick}{every}")
