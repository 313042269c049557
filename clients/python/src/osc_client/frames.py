"""The frames of the command protocol as typed values (docs/protocol.md, "The command protocol").

Each frame type is a frozen dataclass whose fields are the frame's fields, by name. What a field is
on the wire (its type, its count, its place in the payload) and each type's code and payload length
are not written here: they come from the firmware's declarations through ``osc_protocol.json``
(:class:`osc_client.protocol.Protocol`), which checks when it loads that every class below names
exactly the fields declared for its frame, so a frame added or changed in the firmware without its
class here is a named error, not a wrong decode.

Codes stay numbers (``Answer.refusal``, ``State.state``...): their names are the firmware's too, read
with ``Protocol.name_of(NameList.REASONS, answer.refusal)``. A field of several elements is a tuple;
an empty tuple (the default) is encoded as zeros. A scalar field's default is 0, ``0.0`` for a float
(``f32``) one.
"""
from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import ClassVar

Ints = tuple[int, ...]
Floats = tuple[float, ...]


class FrameType(str, Enum):
    """The frame types, named as the firmware declares them (OSC_FRAME_LIST); codes in the JSON."""

    SENSOR = "sensor"
    ACTUATOR = "actuator"
    COMMAND = "command"
    ANSWER = "answer"
    STATE = "state"
    SETPOINT = "setpoint"
    TRACE = "trace"
    SETPOINT_VELOCITY = "setpoint_velocity"
    PARAM = "param"
    PARAM_ANSWER = "param_answer"
    IDENTIFY = "identify"
    CAPTURE = "capture"
    CAPTURE_DATA = "capture_data"
    IDENTIFY_PAYLOAD = "identify_payload"
    IDENTIFY_OFFSET = "identify_offset"


@dataclass(frozen=True)
class Frame:
    """A frame's fields; ``TYPE`` is its frame type."""

    TYPE: ClassVar[FrameType]


# --------------------------------------------------------------------------- client to controller
@dataclass(frozen=True)
class Command(Frame):
    """A command: a verb with its arguments (the flags say which apply), answered by an Answer."""

    TYPE = FrameType.COMMAND
    id: int = 0  # the client's, unique: the answer names it, and a repeat of it is not run again
    verb: int = 0  # NameList.VERBS
    flags: int = 0  # Protocol.command_flags
    position: Floats = ()  # [m], base frame (move_to: absolute, or an offset with the relative flag)
    rpy: Floats = ()  # [rad] roll, pitch, yaw (with the has_rpy flag)
    limits: Floats = ()  # linear v, a, j, angular v, a, j (with the has_limits flag)
    period: int = 0  # stream: ms between setpoints; declare_pose: the pose's code


@dataclass(frozen=True)
class Setpoint(Frame):
    """One setpoint of a running stream (the stream command's id)."""

    TYPE = FrameType.SETPOINT
    id: int = 0
    flags: int = 0  # Protocol.setpoint_flags: end (the last), has_rpy
    position: Floats = ()
    rpy: Floats = ()


@dataclass(frozen=True)
class SetpointVelocity(Frame):
    """A setpoint with the path's velocity there (linear, then angular in the base frame)."""

    TYPE = FrameType.SETPOINT_VELOCITY
    id: int = 0
    flags: int = 0
    position: Floats = ()
    rpy: Floats = ()
    velocity: Floats = ()


@dataclass(frozen=True)
class Param(Frame):
    """A parameter request: get, set, save, load, reset or check (NameList.PARAM_OPS)."""

    TYPE = FrameType.PARAM
    id: int = 0
    op: int = 0
    index: int = 0  # the parameter's index in the table (Protocol.parameters)
    element: int = 0
    value: float = 0.0


@dataclass(frozen=True)
class Capture(Frame):
    """A request of the board's capture (its oscilloscope: docs/protocol.md, "Capture"): arm, trigger, abort,
    status or read (``NameList.CAPTURE_OPS``), answered at once by a CaptureData frame with its id."""

    TYPE = FrameType.CAPTURE
    id: int = 0  # the client's, echoed in the answer
    op: int = 0  # NameList.CAPTURE_OPS
    channels: int = 0  # arm: how many channels (1 to CaptureSpec.channels)
    signal: Ints = ()  # arm: each channel's signal (an index of CaptureSpec.signals)
    element: Ints = ()  # arm: each channel's element of its signal
    trigger: int = 0  # arm: NameList.CAPTURE_TRIGGERS
    level_channel: int = 0  # arm, rising or falling: the channel compared with level
    level: float = 0.0  # that channel's level, in its unit
    pre: int = 0  # arm: samples kept before the trigger's
    divider: int = 0  # arm: a sample every divider ticks (1 or more)
    offset: int = 0  # read: the first value's index, sample x channels + channel


# --------------------------------------------------------------------------- controller to client
@dataclass(frozen=True)
class Answer(Frame):
    """A command's answer, and news of earlier ones: a motion done or aborted, a completion."""

    TYPE = FrameType.ANSWER
    id: int = 0  # the command answered (with outcome not none)
    verb: int = 0
    outcome: int = 0  # NameList.OUTCOMES: none, accepted, refused
    refusal: int = 0  # NameList.REASONS
    cause: int = 0  # fault bits behind a refusal faulted
    done_id: int = 0  # a motion that ended done at rest
    aborted_id: int = 0  # a motion aborted, for the reason in abort
    abort: int = 0  # NameList.REASONS
    completion: int = 0  # NameList.COMPLETIONS: a stop or a homing ended
    state: int = 0  # NameList.MOTION_STATES
    stop: int = 0  # NameList.STOP_CATEGORIES
    queued: int = 0
    tick: int = 0


@dataclass(frozen=True)
class State(Frame):
    """The controller's state, sent periodically (and, all zero, a client's keep-alive)."""

    TYPE = FrameType.STATE
    state: int = 0  # NameList.MOTION_STATES
    stop: int = 0  # NameList.STOP_CATEGORIES
    faults: int = 0  # latched fault bits (Protocol.fault_names)
    queued: int = 0
    running_id: int = 0
    dropped: int = 0  # setpoints overwritten before the tick took them
    x_d: Floats = ()  # the reference pose: x, y, z [m], roll, pitch, yaw [rad]
    x: Floats = ()  # the measured pose
    tick: int = 0
    link: Ints = ()  # the command link's error counters (OSC_LINK_ERROR_LIST's order)
    friction_checked: int = 0  # joints (bit i: joint i + 1) whose set friction the momentum law has checked
    friction_stale: int = 0  # of those, the joints whose set friction no longer fits the arm


@dataclass(frozen=True)
class ParamAnswer(Frame):
    """A parameter request's answer: the element's value and range, or the status that refused it."""

    TYPE = FrameType.PARAM_ANSWER
    id: int = 0
    op: int = 0
    index: int = 0
    element: int = 0
    status: int = 0  # NameList.PARAM_STATUSES (0: ok)
    flags: int = 0  # Protocol.param_flags
    count: int = 0  # parameters in the controller's table
    layout: int = 0  # its layout's hash: another table is another firmware's
    value: float = 0.0
    lo: float = 0.0
    hi: float = 0.0
    margins: Floats = ()  # observer, its b bound, condition (37), loop (check, and a refused gain)


@dataclass(frozen=True)
class Identify(Frame):
    """An identify run's estimate, sent once by the board at the end of the run's motion (docs/protocol.md,
    "Identify frame").

    The coefficients are the drives', in the order the parameters friction_vis, friction_cou, friction_sti
    and armature_correction take them.
    """

    TYPE = FrameType.IDENTIFY
    id: int = 0  # the identify command's id
    status: int = 0  # NameList.IDENTIFY_STATUSES: ok, or why there is no estimate (aborted: the run's motion was)
    samples: int = 0  # the run's samples in the estimate
    lost: int = 0  # samples the board's main loop missed
    condition: float = 0.0  # the regressor's condition number
    prediction_error: float = 0.0  # the worst joint's torque-prediction error, a fraction (rms residual / rms torque)
    friction: Floats = ()  # viscous J1-6 [N m s/rad], Coulomb J1-6, Stribeck J1-6 [N m]; 0 when status is not ok
    friction_sd: Floats = ()  # each coefficient's standard deviation
    identified: int = 0  # bit k set: friction[k] identified (its standard deviation within 2.5 % of it)
    armature: Floats = ()  # [kg m^2] each drive's armature correction (what the model's armature lacks)
    armature_sd: Floats = ()  # their standard deviations


@dataclass(frozen=True)
class IdentifyPayload(Frame):
    """An identify run's estimate of the payload at the flange (the run asked with the command flag payload),
    right after its identify frame (docs/protocol.md, "Identify_payload frame").

    mass, com and inertia are in the form the parameters payload_mass, payload_com and payload_inertia take them;
    pi_sd and identified are the estimated parameters': the mass, its first moment m c (frame 6), its inertia about
    frame 6's origin (Ixx, Ixy, Ixz, Iyy, Iyz, Izz).
    """

    TYPE = FrameType.IDENTIFY_PAYLOAD
    id: int = 0  # the identify command's id
    status: int = 0  # NameList.IDENTIFY_STATUSES: the run's
    mass: float = 0.0  # [kg]; 0 when status is not ok
    com: Floats = ()  # [m] its centre of mass in frame 6
    inertia: Floats = ()  # [kg m^2] about its centre of mass, frame-6 axes: Ixx, Iyy, Izz, Ixy, Ixz, Iyz
    pi_sd: Floats = ()  # the standard deviations: m [kg], m c [kg m], inertia about frame 6's origin [kg m^2]
    identified: int = 0  # bit k set: the k-th of those is identified


@dataclass(frozen=True)
class IdentifyOffset(Frame):
    """An identify run's estimate of each drive's torque offset, right after its identify frame (docs/protocol.md,
    "Identify_offset frame"): the constant torque each drive adds to the one commanded. Reported; no parameter
    takes it."""

    TYPE = FrameType.IDENTIFY_OFFSET
    id: int = 0  # the identify command's id
    status: int = 0  # NameList.IDENTIFY_STATUSES: the run's
    offset: Floats = ()  # [N m] J1-6; 0 when status is not ok
    offset_sd: Floats = ()  # [N m] their standard deviations


@dataclass(frozen=True)
class CaptureData(Frame):
    """A capture frame's answer: the capture's state and set-up after it and, for a read, up to
    ``CaptureSpec.chunk`` of its values (sample by sample, channel by channel, from ``offset``).

    Sample s of a done capture is at tick ``first_tick + s * divider``; the trigger's is sample ``pre``.
    """

    TYPE = FrameType.CAPTURE_DATA
    id: int = 0  # the request's
    op: int = 0  # its op (NameList.CAPTURE_OPS)
    status: int = 0  # NameList.CAPTURE_STATUSES (0: ok)
    state: int = 0  # NameList.CAPTURE_STATES: the capture's after the request
    channels: int = 0  # 0: idle
    signal: Ints = ()
    element: Ints = ()
    trigger: int = 0
    divider: int = 0
    depth: int = 0  # samples per channel held (done)
    pre: int = 0  # samples held before the trigger's (triggered, done; armed: as armed)
    trigger_tick: int = 0  # the trigger's sample's tick, low 32 bits (triggered, done)
    first_tick: int = 0  # the first held sample's tick, low 32 bits (done)
    offset: int = 0  # read: the first value's index
    count: int = 0  # read: the values this frame carries
    values: Floats = ()  # read: values[:count]


# --------------------------------------------------------------------------- the PIL link's frames
@dataclass(frozen=True)
class Sensor(Frame):
    """The plant's readings to the controller over the PIL link."""

    TYPE = FrameType.SENSOR
    seq: int = 0
    counts: Ints = ()
    currents: Ints = ()
    drive: int = 0
    inject: int = 0


@dataclass(frozen=True)
class Actuator(Frame):
    """The controller's DAC codes and its tick's figures, back over the PIL link."""

    TYPE = FrameType.ACTUATOR
    seq: int = 0
    codes: Ints = ()
    faults: int = 0
    state: int = 0
    step_cycles: int = 0
    max_cycles: int = 0
    mean_cycles: int = 0
    tick_max_cycles: int = 0
    stage_cycles: Ints = ()
    stack_used: int = 0
    theta_hat: Floats = ()
    tau_f_hat: Floats = ()
    link: Ints = ()
    rx_gap_max: int = 0
    rx_long_gaps: int = 0


@dataclass(frozen=True)
class Trace(Frame):
    """The reference of a tick (the trajectory and its orientation), for the PIL link's traces."""

    TYPE = FrameType.TRACE
    seq: int = 0
    faults: int = 0
    state: int = 0
    x_d: Floats = ()
    xd_d: Floats = ()
    xdd_d: Floats = ()
    R_ref: Floats = ()


_CLASSES: tuple[type[Frame], ...] = (Sensor, Actuator, Command, Answer, State, Setpoint, Trace, SetpointVelocity,
                                     Param, ParamAnswer, Identify, Capture, CaptureData, IdentifyPayload,
                                     IdentifyOffset)
FRAME_CLASSES: dict[FrameType, type[Frame]] = {cls.TYPE: cls for cls in _CLASSES}
"""The class of each frame type."""
