"""The client: commands out, answers and state in, and what became of each command.

A command is one frame with a fresh id; the controller answers it once (accepted or refused), and a
motion it accepted ends in exactly one later answer naming it: done, or aborted with a reason.
Without an answer a client sends the same frame again (every ``Client.RESEND`` seconds): the
controller runs an id once and answers a repeat with the answer it gave (docs/protocol.md, "The
command protocol").
"""
from __future__ import annotations

import dataclasses
import random
import time
from dataclasses import dataclass
from enum import Enum
from typing import Callable, Sequence, TypeVar

from .errors import ClientError
from .frames import (Answer, Capture, CaptureData, Command, Floats, Frame, Identify, IdentifyOffset, IdentifyPayload,
                     Param, ParamAnswer, Setpoint, SetpointVelocity, State)
from .parser import Parser
from .paths import PathPoint
from .protocol import NameList, Protocol
from .transport import SerialTransport, Transport

RunFrame = TypeVar("RunFrame", Identify, IdentifyOffset, IdentifyPayload)
"""A frame a board sends at the end of an identify run."""

MOTION_VERBS = ("move_to", "paper", "stream", "home", "identify")
"""The verbs whose acceptance starts a motion, which ends later (done or aborted)."""


class Status(Enum):
    """What became of a command, as far as the client knows."""

    ACCEPTED = "accepted"  # answered accepted; a motion not ended (yet)
    DONE = "done"  # a motion done at rest, a stop or disable at rest, any other command accepted
    REFUSED = "refused"  # answered refused (Outcome.reason)
    ABORTED = "aborted"  # a motion accepted, then aborted (Outcome.reason)
    TIMEOUT = "timeout"  # no answer, or no end, within the time


@dataclass
class Outcome:
    """A command's outcome: its status, the reason of a refusal or abort, the answer that said so."""

    status: Status
    id: int = 0
    reason: str = "none"  # NameList.REASONS: why refused or aborted
    cause: int = 0  # a refusal faulted: the fault bits
    cause_names: str = "none"  # those bits' names
    answer: Answer | None = None
    skipped: int = 0  # a stream's setpoints not sent: the client fell behind its schedule

    def ok(self) -> bool:
        """Accepted or done."""
        return self.status in (Status.ACCEPTED, Status.DONE)

    def text(self) -> str:
        """As oscctl prints it: ``done``, ``refused: not_enabled``, ``refused: faulted (estop)`` ..."""
        text = self.status.value
        if self.status in (Status.REFUSED, Status.ABORTED):
            text += f": {self.reason}"
        if self.status == Status.REFUSED and self.reason == "faulted":
            text += f" ({self.cause_names})"
        return text


class Client:
    """The command protocol over a transport: a port's path (a serial device or pseudo-terminal) or
    any :class:`Transport`.

    Each command method sends its frame and returns the command's id; ``wait_answer(id)`` waits for
    its answer, ``wait_done(id)`` for its end. While waiting the client reads every frame: answers
    are kept (``answers``, ``on_answer``), state frames too (``latest_state``, ``on_state``), and the
    last parameter answer, identify frame and capture answer (``param_answer``, ``last_identify``,
    ``capture_answer``). The board's capture (its oscilloscope) is ``osc_client.capture.Oscilloscope``'s.

    A board whose encoders are local stops a running motion (aborted link_silent) when no frame comes
    from the host for 0.5 s: while it waits, the client sends a keep-alive frame (an all-zero state
    frame, which a controller takes as link activity and otherwise ignores) whenever it has sent
    nothing for ``keepalive`` seconds (0: none).
    """

    HISTORY = 1024  # answers kept
    RESEND = 0.5  # seconds without an answer before a command is sent again
    SENT_KEPT = 64  # the frames of the last commands, kept to be resent
    KEEPALIVE = 0.1  # seconds, oscctl's default

    def __init__(self, port: str | Transport, baud: int = 115200, protocol: Protocol | None = None,
                 keepalive: float = KEEPALIVE, first_id: int | None = None) -> None:
        """Opens the port (or takes the transport). ``first_id``: the first command's id (default
        random, so that no earlier client's answers are taken for this one's)."""
        self.protocol = protocol or Protocol()
        self.transport: Transport = SerialTransport(port, baud) if isinstance(port, str) else port
        self.keepalive = keepalive
        self.parser = Parser(self.protocol)
        self.next_id = random.randint(1, 2**30) if first_id is None else first_id
        self.answers: list[Answer] = []
        self.latest_state: State | None = None
        self.states_seen = 0
        self.param_answer: ParamAnswer | None = None
        self.last_identify: Identify | None = None  # the last identify frame (an identify run's estimate)
        self.last_identify_payload: IdentifyPayload | None = None  # the last identify_payload frame
        self.last_identify_offset: IdentifyOffset | None = None  # the last identify_offset frame
        self.capture_answer: CaptureData | None = None  # the last capture_data frame (a capture request's answer)
        self.on_answer: Callable[[Answer], None] | None = None
        self.on_state: Callable[[State], None] | None = None
        self._sent: dict[int, bytes] = {}  # the frames of the last SENT_KEPT commands, by id (resent unchanged)
        self._last_write = time.monotonic()

    def close(self) -> None:
        """Closes the transport."""
        self.transport.close()

    # ------------------------------------------------------------------ commands: each returns its id
    def command(self, verb: str, position: Sequence[float] = (0.0, 0.0, 0.0), rpy: Sequence[float] | None = None,
                relative: bool = False, replace: bool = False, limits: Sequence[float] | None = None,
                period: int = 0, payload: bool = False) -> int:
        """Sends one command frame; its id.

        ``verb``: a name of NameList.VERBS; ``rpy`` [rad] or None; ``limits``: six numbers (linear v,
        a, j, angular v, a, j) or None for the configured maxima; ``period``: a stream's, in ms.
        """
        cid = self._new_id()
        flag = self.protocol.command_flags
        flags = ((flag["relative"] if relative else 0) | (flag["has_rpy"] if rpy else 0)
                 | (flag["replace"] if replace else 0) | (flag["has_limits"] if limits else 0)
                 | (flag["payload"] if payload else 0))
        frame = self.protocol.encode(Command(
            id=cid, verb=self.protocol.code_of(NameList.VERBS, verb), flags=flags, position=tuple(position),
            rpy=tuple(rpy or ()), limits=tuple(limits or ()), period=period))
        self._sent[cid] = frame
        if len(self._sent) > self.SENT_KEPT:
            del self._sent[next(iter(self._sent))]
        self._write(frame)
        return cid

    def enable(self) -> int:
        """Torque on, holding the measured pose."""
        return self.command("enable")

    def disable(self) -> int:
        """Torque off (wait_done: at rest)."""
        return self.command("disable")

    def stop(self) -> int:
        """A controlled stop of any motion, the queue dropped (wait_done: at rest)."""
        return self.command("stop")

    def clear(self) -> int:
        """Clears the latched faults."""
        return self.command("clear")

    def paper(self) -> int:
        """The paper's motion (trajectory (68))."""
        return self.command("paper")

    def identify(self, payload: bool = False) -> int:
        """An identification run: the excitation motion about the held joint angles (80 s), planned and checked
        on the board first (refused by name: out_of_workspace, near_singular, over_limit, unstable_loop);
        wait_done for its end, then wait_identify for the board's estimate. With ``payload`` (the flag payload) the
        run estimates the payload at the flange too: wait_identify_payload."""
        return self.command("identify", payload=payload)

    def home(self) -> int:
        """Homing: each motor to its index pulse from the pots' coarse angles; wait_done for its end."""
        return self.command("home")

    def declare_pose(self, pose: str) -> int:
        """The arm stands at the named pose (Protocol.poses; torque off): its code in period."""
        poses = self.protocol.poses
        if pose not in poses:
            raise ClientError(f"'{pose}' is not a named pose: {', '.join(poses)}")
        return self.command("declare_pose", period=poses.index(pose))

    def move_to(self, position: Sequence[float], rpy: Sequence[float] | None = None, relative: bool = False,
                replace: bool = False, limits: Sequence[float] | None = None) -> int:
        """A jerk-limited move of the wrist centre to ``position`` [m] (and ``rpy`` [rad]), queued
        behind the running motion, or re-targeting it (``replace``)."""
        return self.command("move_to", position, rpy, relative, replace, limits)

    def limits(self, v: float | None = None, a: float | None = None, j: float | None = None) -> Floats | None:
        """Six limits: the linear ones given, the others the configured maxima (None when none given)."""
        if v is None and a is None and j is None:
            return None
        lin = self.protocol.limits.linear
        return (v or lin[0], a or lin[1], j or lin[2]) + self.protocol.limits.angular

    def stream(self, points: Sequence[PathPoint], has_rpy: bool, rate_hz: float, relative: bool = False,
               limits: Sequence[float] | None = None, answer_timeout: float = 10, velocity: bool = False) -> Outcome:
        """Streams a path: the stream command, its answer awaited, then one setpoint per period
        paced by the wall clock, the last with the end flag (with ``velocity``, setpoint_velocity
        frames: no delay of one period).

        The stream command's outcome once every setpoint is sent (accepted: ``wait_done(outcome.id)``
        for its end), or its refusal, an abort while sending, a timeout. A setpoint whose successor
        is due already is skipped (``Outcome.skipped``), not sent in a burst the board would only
        overwrite.
        """
        period = 1000.0 / rate_hz
        if abs(period - round(period)) > 1e-9 or not 1 <= round(period) <= self.protocol.stream_max_period:
            raise ClientError(f"rate {rate_hz:g} Hz: 1000 / N Hz for a whole N from 1 to "
                              f"{self.protocol.stream_max_period} (1000, 500, 250, 100, 50, 20, 10 ...)")
        if not points:
            raise ClientError("a stream needs at least one setpoint")
        cid = self.command("stream", relative=relative, limits=limits, period=int(round(period)))
        outcome = self.wait_answer(cid, answer_timeout)
        if outcome.status != Status.ACCEPTED:
            return outcome
        flag = self.protocol.setpoint_flags
        t0, step = time.monotonic(), 1.0 / rate_hz
        for n, point in enumerate(points):
            last = n + 1 == len(points)
            if not last and time.monotonic() >= t0 + (n + 1) * step:
                outcome.skipped += 1
                continue
            if self._read_until(t0 + n * step, lambda: self._ended(cid)):
                ended = self._evaluate(cid, until_done=True)
                ended.skipped = outcome.skipped
                return ended
            flags = (flag["end"] if last else 0) | (flag["has_rpy"] if has_rpy else 0)
            rpy = tuple(point.rpy) if has_rpy else ()
            frame: Frame = (SetpointVelocity(cid, flags, tuple(point.position), rpy, tuple(point.velocity))
                            if velocity else Setpoint(cid, flags, tuple(point.position), rpy))
            self.send(frame)
        return outcome

    def param(self, op: str, index: int = 0, element: int = 0, value: float = 0.0,
              timeout: float = 5.0) -> ParamAnswer:
        """A parameter request (``op``: get, set, save, load, reset, check) and its answer.

        A timeout, or an answer from a firmware with another parameter table, raises ClientError.
        """
        cid = self._new_id()
        self.param_answer = None
        self.send(Param(cid, self.protocol.code_of(NameList.PARAM_OPS, op), index, element, value))
        if not self._read_until(time.monotonic() + timeout,
                                lambda: self.param_answer is not None and self.param_answer.id == cid):
            raise ClientError(f"param {op}: no answer within {timeout:g} s")
        answer = self.param_answer
        assert answer is not None
        mine = (self.protocol.param_layout, len(self.protocol.parameters))
        if (answer.layout, answer.count) != mine:
            raise ClientError(f"param: the controller's parameter table (layout {answer.layout}, {answer.count} "
                              f"parameters) is not this client's (layout {mine[0]}, {mine[1]}): "
                              "use the client of its build")
        return answer

    def capture(self, request: Capture, timeout: float = 5.0) -> CaptureData:
        """A capture request (its id replaced by a fresh one) and its capture_data answer, the one with its id.

        A timeout raises ClientError (``osc_client.capture.Oscilloscope`` builds the requests).
        """
        cid = self._new_id()
        self.capture_answer = None
        self.send(dataclasses.replace(request, id=cid))
        if not self._read_until(time.monotonic() + timeout,
                                lambda: self.capture_answer is not None and self.capture_answer.id == cid):
            op = self.protocol.name_of(NameList.CAPTURE_OPS, request.op)
            raise ClientError(f"capture {op}: no answer within {timeout:g} s (a board without the capture, or "
                              "a link that lost the frame)")
        answer = self.capture_answer
        assert answer is not None
        return answer

    def send(self, *frames: Frame) -> None:
        """Sends frames as they are, in one write (no id given, none kept for a resend)."""
        self._write(b"".join(self.protocol.encode(f) for f in frames))

    # ------------------------------------------------------------------ answers and state
    def state(self, timeout: float = 5.0) -> State | None:
        """The first state frame received after this call; None on a timeout."""
        seen = self.states_seen
        if self._read_until(time.monotonic() + timeout, lambda: self.states_seen > seen):
            return self.latest_state
        return None

    def wait_answer(self, cid: int, timeout: float = 10.0) -> Outcome:
        """Accepted or refused, or a timeout. Without an answer the command is sent again, the same
        frame, every RESEND seconds."""
        self._read_until(time.monotonic() + timeout, lambda: self._evaluate(cid).status != Status.TIMEOUT,
                         resend=cid)
        return self._evaluate(cid)

    def wait_done(self, cid: int, timeout: float = 120.0) -> Outcome:
        """A motion done at rest or aborted (the reason); a stop or disable done at rest; any other
        command done once accepted; refused (the reason); or a timeout."""
        self._read_until(time.monotonic() + timeout, lambda: self._evaluate(cid, until_done=True).status not in
                         (Status.TIMEOUT, Status.ACCEPTED), resend=cid)
        outcome = self._evaluate(cid, until_done=True)
        if outcome.status == Status.ACCEPTED:
            outcome.status = Status.TIMEOUT
        return outcome

    def wait_identify(self, cid: int, timeout: float = 2.0) -> Identify | None:
        """The identify frame of the identify run ``cid``: received already, or within ``timeout`` seconds.

        Every board sends it once, right after the answer of the tick the run's motion ended in (the virtual
        board, the QEMU images), or from its main loop within a few ticks of it (the STM32F4 app); ``wait_done(cid)``
        may have read it already: the estimate when the motion was done, status aborted when it was aborted. None
        when none came: a firmware from before the boards estimated runs the motion alone, or the frame was lost.
        """
        return self._wait_run_frame(lambda: self.last_identify, cid, timeout)

    def wait_identify_offset(self, cid: int, timeout: float = 2.0) -> IdentifyOffset | None:
        """The identify_offset frame of the identify run ``cid`` (each drive's torque offset), sent right after its
        identify frame: received already, or within ``timeout`` seconds; None when none came (a firmware from
        before it was sent)."""
        return self._wait_run_frame(lambda: self.last_identify_offset, cid, timeout)

    def wait_identify_payload(self, cid: int, timeout: float = 2.0) -> IdentifyPayload | None:
        """The identify_payload frame of the identify run ``cid`` (asked with ``payload``), sent after its identify
        and identify_offset frames: received already, or within ``timeout`` seconds; None when none came."""
        return self._wait_run_frame(lambda: self.last_identify_payload, cid, timeout)

    def _wait_run_frame(self, last: Callable[[], RunFrame | None], cid: int, timeout: float) -> RunFrame | None:
        """The last frame of a run's kind (``last()``) once it is run ``cid``'s: received already, or within
        ``timeout`` seconds."""
        def mine() -> bool:
            f = last()
            return f is not None and f.id == cid
        self._read_until(time.monotonic() + timeout, mine)
        return last() if mine() else None

    def pump(self, timeout: float, until: Callable[[], bool] | None = None) -> bool:
        """Reads and dispatches frames (on_answer, on_state) for ``timeout`` seconds (``inf``: for ever), or
        until ``until()`` (checked before each read, 0.05 s at most apart), keeping the link alive; True
        when ``until()`` ended it."""
        return self._read_until(time.monotonic() + timeout, until or (lambda: False))

    # ------------------------------------------------------------------ inside
    def _new_id(self) -> int:
        cid = self.next_id
        self.next_id = self.next_id % 0xFFFFFFFF + 1
        return cid

    def _write(self, data: bytes) -> None:
        self.transport.write(data)
        self._last_write = time.monotonic()

    def _keep_alive(self) -> None:
        """An all-zero state frame when nothing was sent for ``keepalive`` seconds: link activity for a
        board that stops a motion when its command link goes silent."""
        if self.keepalive and time.monotonic() - self._last_write >= self.keepalive:
            self.send(State())

    def _read_until(self, deadline: float, done: Callable[[], bool], resend: int | None = None) -> bool:
        """Reads frames until ``done()`` or the deadline (False). ``resend``: a command's id, whose frame
        is sent again every RESEND seconds while it has no answer."""
        last_rx = sent = time.monotonic()
        while not done():
            now = time.monotonic()
            left = deadline - now
            if left <= 0:
                return False
            if resend in self._sent and now - sent >= self.RESEND:
                if self._evaluate(resend).status == Status.TIMEOUT:  # no answer yet
                    self._write(self._sent[resend])
                sent = now
            self._keep_alive()
            data = self.transport.read(min(left, 0.05))
            if data:
                last_rx = time.monotonic()
                frames = self.parser.feed(data)
            elif time.monotonic() - last_rx >= Parser.FRAME_TIMEOUT:
                frames = self.parser.expire()
            else:
                frames = []
            for raw in frames:
                self._dispatch(self.protocol.decode(raw.type, raw.payload))
        return True

    def _dispatch(self, frame: Frame) -> None:
        if isinstance(frame, ParamAnswer):
            self.param_answer = frame
        elif isinstance(frame, Identify):
            self.last_identify = frame
        elif isinstance(frame, IdentifyPayload):
            self.last_identify_payload = frame
        elif isinstance(frame, IdentifyOffset):
            self.last_identify_offset = frame
        elif isinstance(frame, CaptureData):
            self.capture_answer = frame
        elif isinstance(frame, Answer):
            self.answers = (self.answers + [frame])[-self.HISTORY:]
            if self.on_answer:
                self.on_answer(frame)
        elif isinstance(frame, State):
            self.latest_state = frame
            self.states_seen += 1
            if self.on_state:
                self.on_state(frame)

    def _ended(self, cid: int) -> bool:
        return self._evaluate(cid, until_done=True).status in (Status.DONE, Status.ABORTED)

    def _evaluate(self, cid: int, until_done: bool = False) -> Outcome:
        """The command's outcome as far as the answers so far tell (TIMEOUT: no answer yet)."""
        p = self.protocol
        name = p.name_of
        motion_verbs = {p.code_of(NameList.VERBS, v) for v in MOTION_VERBS}
        accepted = wait_rest = motion = False
        outcome = Outcome(Status.TIMEOUT, cid)
        for a in self.answers:
            if not accepted:
                if a.id != cid or name(NameList.OUTCOMES, a.outcome) == "none":
                    continue
                outcome.answer = a
                if name(NameList.OUTCOMES, a.outcome) == "refused":
                    outcome.status, outcome.reason = Status.REFUSED, name(NameList.REASONS, a.refusal)
                    outcome.cause, outcome.cause_names = a.cause, p.fault_names(a.cause)
                    return outcome
                accepted, outcome.status = True, Status.ACCEPTED
                if not until_done:
                    return outcome
                motion = a.verb in motion_verbs
                wait_rest = not motion and name(NameList.MOTION_STATES, a.state) == "stopping"
                if not motion and not wait_rest:
                    outcome.status = Status.DONE
                    return outcome
                continue
            rested = wait_rest and name(NameList.COMPLETIONS, a.completion) != "none"
            if rested or motion and a.done_id == cid:
                outcome.answer, outcome.status = a, Status.DONE
                return outcome
            # A motion ends in exactly one answer naming it: done, or aborted with a reason (a move still
            # queued when the motion ahead of it was stopped, re-targeted or faulted: dropped).
            if motion and a.aborted_id == cid and name(NameList.REASONS, a.abort) != "none":
                outcome.answer, outcome.status, outcome.reason = a, Status.ABORTED, name(NameList.REASONS, a.abort)
                return outcome
        return outcome
