"""Recorded byte streams: a transport that records what a board sent, and one that plays it back.

A recording (tests/data/*.json, written by record_streams.py against the virtual board) holds one
run of the command line: its arguments, the first command id it used, the board's bytes in the
chunks the client read them, the first frame the client wrote, and the output and exit status the
run printed. Played back with the same first id, the client must print the same and exit the same.
"""
from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from osc_client import Transport

DATA = Path(__file__).with_name("data")


@dataclass
class Recording:
    """One command-line run against a board, as recorded."""

    name: str
    argv: list[str]
    first_id: int
    board: list[bytes]  # the board's bytes, in the chunks the client read
    first_write: bytes  # the first frame the client wrote (its command, a keep-alive; b"" for none)
    stdout: str
    exit: int

    @staticmethod
    def load(path: Path) -> Recording:
        r: dict[str, Any] = json.loads(path.read_text())
        return Recording(path.stem, list(r["argv"]), int(r["first_id"]), [bytes.fromhex(c) for c in r["board"]],
                         bytes.fromhex(r["first_write"]), str(r["stdout"]), int(r["exit"]))

    def save(self, path: Path) -> None:
        path.write_text(json.dumps({"argv": self.argv, "first_id": self.first_id,
                                    "board": [c.hex() for c in self.board], "first_write": self.first_write.hex(),
                                    "stdout": self.stdout, "exit": self.exit}, indent=1) + "\n")


def recordings() -> list[Recording]:
    """Every recording of tests/data."""
    return [Recording.load(p) for p in sorted(DATA.glob("*.json"))]


@dataclass
class ReplayTransport:
    """Plays a board's chunks back, one a read, and keeps what the client writes."""

    chunks: list[bytes]
    written: list[bytes] = field(default_factory=list)
    closed: bool = False

    def read(self, timeout: float) -> bytes:
        if self.chunks:
            return self.chunks.pop(0)
        time.sleep(min(timeout, 0.005))  # the recording is over: a silent board
        return b""

    def write(self, data: bytes) -> None:
        self.written.append(data)

    def close(self) -> None:
        self.closed = True


@dataclass
class RecordingTransport:
    """Another transport, its reads recorded."""

    inner: Transport
    read_chunks: list[bytes] = field(default_factory=list)
    written: list[bytes] = field(default_factory=list)

    def read(self, timeout: float) -> bytes:
        data = self.inner.read(timeout)
        if data:
            self.read_chunks.append(data)
        return data

    def write(self, data: bytes) -> None:
        self.written.append(data)
        self.inner.write(data)

    def close(self) -> None:
        self.inner.close()
