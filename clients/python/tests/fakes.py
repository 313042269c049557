"""Scripted boards: a transport whose controller answers each command as a test says, and one that sends
state frames."""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Iterator

from osc_client import Answer, Command, Frame, NameList, Param, Parser, Protocol, State

Reply = Callable[[Command], list[Frame]]
ParamReply = Callable[[Param], list[Frame]]


@dataclass
class FakeBoard:
    """Answers each command frame the client writes through ``reply`` (the client reads the frames
    it returns next), each param frame through ``param_reply`` (none: no answer), and keeps every frame
    the client sent."""

    protocol: Protocol
    reply: Reply
    sent: list[Frame] = field(default_factory=list)
    pending: bytes = b""
    param_reply: ParamReply | None = None

    def __post_init__(self) -> None:
        self.parser = Parser(self.protocol)

    def read(self, timeout: float) -> bytes:
        data, self.pending = self.pending, b""
        if not data:
            time.sleep(min(timeout, 0.002))
        return data

    def write(self, data: bytes) -> None:
        for raw in self.parser.feed(data):
            frame = self.protocol.decode(raw.type, raw.payload)
            self.sent.append(frame)
            if isinstance(frame, Command):
                self.pending += b"".join(self.protocol.encode(f) for f in self.reply(frame))
            elif isinstance(frame, Param) and self.param_reply is not None:
                self.pending += b"".join(self.protocol.encode(f) for f in self.param_reply(frame))

    def close(self) -> None:
        pass

    def commands(self) -> list[Command]:
        """The command frames the client sent, resends included."""
        return [f for f in self.sent if isinstance(f, Command)]


def answer(p: Protocol, command: Command, outcome: str = "accepted", refusal: str = "none",
           state: str = "holding", **fields: int) -> Answer:
    """The answer to a command (its id and verb) with the named outcome, refusal and motion state."""
    return Answer(id=command.id, verb=command.verb, outcome=p.code_of(NameList.OUTCOMES, outcome),
                  refusal=p.code_of(NameList.REASONS, refusal), state=p.code_of(NameList.MOTION_STATES, state),
                  **fields)


@dataclass
class StateFeed:
    """A board that sends state frames: the next of ``frames`` at each read (after ``period`` seconds, its
    pace), silence once they are over; it keeps every frame the client wrote (its keep-alives)."""

    protocol: Protocol
    frames: Iterator[State]
    period: float = 0.0
    sent: list[Frame] = field(default_factory=list)
    closed: bool = False

    def __post_init__(self) -> None:
        self.parser = Parser(self.protocol)

    def read(self, timeout: float) -> bytes:
        if self.period:
            time.sleep(min(timeout, self.period))
        frame = next(self.frames, None)
        if frame is None:
            time.sleep(min(timeout, 0.005))
            return b""
        return self.protocol.encode(frame)

    def write(self, data: bytes) -> None:
        self.sent += [self.protocol.decode(raw.type, raw.payload) for raw in self.parser.feed(data)]

    def close(self) -> None:
        self.closed = True
