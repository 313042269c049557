"""What becomes of a command: the client's outcomes against a scripted board."""
from __future__ import annotations

import time

import pytest

from fakes import FakeBoard, answer
from osc_client import (Answer, Client, ClientError, Command, Frame, Identify, NameList, Outcome, Param, ParamAnswer,
                        PathPoint, Protocol, Setpoint, State, Status)
from replay import ReplayTransport


def client(p: Protocol, board: FakeBoard, keepalive: float = 0.0) -> Client:
    return Client(board, protocol=p, keepalive=keepalive, first_id=100)


def test_accepted_then_done(protocol: Protocol) -> None:
    """A move accepted, then done in a later answer naming it."""
    board = FakeBoard(protocol, lambda c: [answer(protocol, c, state="moving"), Answer(done_id=c.id)])
    c = client(protocol, board)
    cid = c.move_to((0.0, 0.02, 0.0), relative=True)
    assert cid == 100
    assert c.wait_answer(cid, 2).status == Status.ACCEPTED
    done = c.wait_done(cid, 2)
    assert (done.status, done.ok(), done.text()) == (Status.DONE, True, "done")
    (sent,) = board.commands()
    assert protocol.name_of(NameList.VERBS, sent.verb) == "move_to"
    assert sent.flags == protocol.command_flags["relative"] and sent.position == pytest.approx((0, 0.02, 0))


def test_refused_with_its_reason(protocol: Protocol) -> None:
    board = FakeBoard(protocol, lambda c: [answer(protocol, c, "refused", "not_enabled")])
    o = client(protocol, board).wait_done(client(protocol, board).enable(), 2)
    assert (o.status, o.reason, o.ok(), o.text()) == (Status.REFUSED, "not_enabled", False, "refused: not_enabled")


def test_refused_faulted_names_the_faults(protocol: Protocol) -> None:
    estop = 1 << protocol.names(NameList.FAULTS).index("estop")
    board = FakeBoard(protocol, lambda c: [answer(protocol, c, "refused", "faulted", cause=estop)])
    c = client(protocol, board)
    o = c.wait_answer(c.enable(), 2)
    assert o.text() == "refused: faulted (estop)" and o.cause == estop


def test_aborted_with_its_reason(protocol: Protocol) -> None:
    dropped = protocol.code_of(NameList.REASONS, "dropped")
    board = FakeBoard(protocol, lambda c: [answer(protocol, c), Answer(aborted_id=c.id, abort=dropped)])
    c = client(protocol, board)
    o = c.wait_done(c.move_to((0.0, 0.0, 0.01)), 2)
    assert (o.status, o.reason, o.text()) == (Status.ABORTED, "dropped", "aborted: dropped")


def test_another_commands_end_is_not_this_ones(protocol: Protocol) -> None:
    board = FakeBoard(protocol, lambda c: [answer(protocol, c), Answer(done_id=c.id + 1)])
    c = client(protocol, board)
    o = c.wait_done(c.move_to((0.0, 0.0, 0.01)), 0.2)
    assert o.status == Status.TIMEOUT and o.text() == "timeout"


def test_a_stop_is_done_at_rest(protocol: Protocol) -> None:
    """Accepted while stopping: done once an answer says the stop completed."""
    stopped = protocol.code_of(NameList.COMPLETIONS, "stopped")
    board = FakeBoard(protocol, lambda c: [answer(protocol, c, state="stopping"), Answer(completion=stopped)])
    c = client(protocol, board)
    cid = c.stop()
    assert c.wait_answer(cid, 2).status == Status.ACCEPTED
    assert c.wait_done(cid, 2).status == Status.DONE


def test_a_command_without_motion_is_done_once_accepted(protocol: Protocol) -> None:
    board = FakeBoard(protocol, lambda c: [answer(protocol, c)])
    c = client(protocol, board)
    assert c.wait_done(c.clear(), 2).status == Status.DONE


def test_no_answer_is_a_timeout_and_the_command_is_resent(protocol: Protocol) -> None:
    board = FakeBoard(protocol, lambda c: [])
    c = client(protocol, board)
    c.RESEND = 0.05
    o = c.wait_answer(c.enable(), 0.3)
    assert o.status == Status.TIMEOUT and not o.ok()
    sent = board.commands()
    assert len(sent) >= 3 and all(s == sent[0] for s in sent)  # the same frame, the same id


def test_a_resend_answered_is_taken(protocol: Protocol) -> None:
    """The board misses the first frame; the resend is answered."""
    seen: list[Command] = []

    def reply(c: Command) -> list[Frame]:
        seen.append(c)
        return [answer(protocol, c)] if len(seen) > 1 else []
    board = FakeBoard(protocol, reply)
    c = client(protocol, board)
    c.RESEND = 0.05
    assert c.wait_answer(c.enable(), 2).status == Status.ACCEPTED
    assert len(seen) == 2


def test_keep_alive_while_waiting(protocol: Protocol) -> None:
    board = FakeBoard(protocol, lambda c: [])
    c = client(protocol, board, keepalive=0.02)
    c.pump(0.2)
    keepalives = [f for f in board.sent if isinstance(f, State)]
    assert len(keepalives) >= 3 and all(k == State(x_d=(0.0,) * 6, x=(0.0,) * 6, link=(0,) * 7) for k in keepalives)


def test_state_and_callbacks(protocol: Protocol) -> None:
    board = FakeBoard(protocol, lambda c: [answer(protocol, c), State(state=1, tick=9)])
    c = client(protocol, board)
    answers: list[Answer] = []
    states: list[State] = []
    c.on_answer, c.on_state = answers.append, states.append
    c.clear()
    s = c.state(2)
    assert s is not None and s.tick == 9 and protocol.name_of(NameList.MOTION_STATES, s.state) == "holding"
    assert len(answers) == 1 and states == [s]
    assert c.state(0.05) is None  # none after this call


def test_wait_identify_takes_the_frame_read_with_the_end(protocol: Protocol) -> None:
    """The board sends the estimate right after the end's answer: wait_done reads it, wait_identify returns it at
    once; another run's frame is not this one's."""
    board = FakeBoard(protocol, lambda c: [answer(protocol, c, state="moving"), Answer(done_id=c.id),
                                           Identify(id=c.id + 7, samples=1), Identify(id=c.id, samples=16000)])
    c = client(protocol, board)
    cid = c.identify()
    assert c.wait_done(cid, 2).status == Status.DONE
    assert c.last_identify is not None and c.last_identify.samples == 16000
    t0 = time.monotonic()
    f = c.wait_identify(cid, 60)
    # Returned at once, not after the 60 s it may wait (a generous margin for a loaded machine).
    assert f is not None and (f.id, f.samples) == (cid, 16000) and time.monotonic() - t0 < 30
    t0 = time.monotonic()
    assert c.wait_identify(cid + 7, 0.2) is None  # its frame was not the last one
    assert time.monotonic() - t0 >= 0.2


def test_wait_identify_reads_a_frame_that_comes_later(protocol: Protocol) -> None:
    late = protocol.encode(Identify(id=100, status=protocol.code_of(NameList.IDENTIFY_STATUSES, "aborted")))
    c = Client(ReplayTransport([b"", b"", protocol.encode(Identify(id=99)), b"", late]), protocol=protocol,
               keepalive=0, first_id=100)
    f = c.wait_identify(100, 2)
    assert f is not None and protocol.name_of(NameList.IDENTIFY_STATUSES, f.status) == "aborted"


def test_wait_identify_without_a_frame_is_none(protocol: Protocol) -> None:
    c = client(protocol, FakeBoard(protocol, lambda c: []))
    t0 = time.monotonic()
    assert c.wait_identify(100, 0.2) is None and c.last_identify is None
    assert time.monotonic() - t0 >= 0.2


def test_param_answer_and_another_table(protocol: Protocol) -> None:
    table = (protocol.param_layout, len(protocol.parameters))
    answers = {"mine": table, "another": (table[0] + 1, table[1])}
    kind = ["mine"]

    class ParamBoard(FakeBoard):
        def write(self, data: bytes) -> None:
            for raw in self.parser.feed(data):
                q = protocol.decode(raw.type, raw.payload)
                if isinstance(q, Param):
                    layout, count = answers[kind[0]]
                    self.pending += protocol.encode(ParamAnswer(id=q.id, op=q.op, index=q.index, element=q.element,
                                                                layout=layout, count=count, value=97.0))
    c = client(protocol, ParamBoard(protocol, lambda c: []))
    ks = protocol.parameter("ks")
    assert ks is not None
    a = c.param("get", ks.index, 2, timeout=2)
    assert (a.index, a.element, a.value) == (ks.index, 2, 97.0)
    kind[0] = "another"
    with pytest.raises(ClientError, match="is not this client's"):
        c.param("get", ks.index, 0, timeout=2)


def test_param_without_answer_is_an_error(protocol: Protocol) -> None:
    c = client(protocol, FakeBoard(protocol, lambda c: []))
    with pytest.raises(ClientError, match="param save: no answer within 0.1 s"):
        c.param("save", timeout=0.1)


def test_stream_sends_each_setpoint_the_last_with_end(protocol: Protocol) -> None:
    board = FakeBoard(protocol, lambda c: [answer(protocol, c)])
    c = client(protocol, board)
    points = [PathPoint((0.0, 0.001 * k, 0.0), (0.0, 0.0, 0.0)) for k in range(3)]
    o = c.stream(points, False, 100, relative=True)
    assert o.status == Status.ACCEPTED and o.skipped == 0
    (command,) = board.commands()
    assert command.period == 10 and command.flags == protocol.command_flags["relative"]
    setpoints = [f for f in board.sent if isinstance(f, Setpoint)]
    assert [s.position[1] for s in setpoints] == pytest.approx([0.0, 0.001, 0.002])
    assert [s.flags for s in setpoints] == [0, 0, protocol.setpoint_flags["end"]]
    assert all(s.id == command.id for s in setpoints)


@pytest.mark.parametrize("rate", [3.0, 2000.0, 5.0])
def test_stream_rate_must_be_1000_over_n(protocol: Protocol, rate: float) -> None:
    c = client(protocol, FakeBoard(protocol, lambda c: []))
    with pytest.raises(ClientError, match="1000 / N Hz"):
        c.stream([PathPoint((0.0,) * 3, (0.0,) * 3)], False, rate)


def test_unknown_pose_is_an_error(protocol: Protocol) -> None:
    c = client(protocol, FakeBoard(protocol, lambda c: []))
    with pytest.raises(ClientError, match="'north' is not a named pose: start, zero"):
        c.declare_pose("north")


def test_limits(protocol: Protocol) -> None:
    c = client(protocol, FakeBoard(protocol, lambda c: []))
    assert c.limits() is None
    assert c.limits(v=0.01) == (0.01,) + protocol.limits.linear[1:] + protocol.limits.angular


def test_outcome_text() -> None:
    assert Outcome(Status.ABORTED, reason="stop_command").text() == "aborted: stop_command"
    assert Outcome(Status.ACCEPTED).ok() and not Outcome(Status.TIMEOUT).ok()
    assert Outcome(Status.REFUSED, reason="faulted", cause_names="estop,tracking").text() == \
        "refused: faulted (estop,tracking)"
