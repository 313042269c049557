"""Frames out of a byte stream, with the protocol's resynchronisation.

docs/protocol.md, "Framing and resynchronisation": the parser hunts for the sync pair, then reads the
type, the length, the payload and the CRC. A frame that fails (an unknown type, a length that is not
its type's, a bad CRC, or one cut short: ``expire``) gives up its sync pair only, and the bytes after
that pair are scanned again, so a good frame that starts inside a bad one is still found.
"""
from __future__ import annotations

import struct
from typing import NamedTuple

from .frames import FrameType
from .protocol import Protocol

HEADER = 4  # sync pair, type, length
CRC = 2


class RawFrame(NamedTuple):
    """A valid frame's type and payload, not yet decoded (``Protocol.decode``)."""

    type: FrameType
    payload: bytes


class Parser:
    """Feed it bytes as they come; it returns each complete, valid frame once."""

    FRAME_TIMEOUT = 0.02
    """Seconds of silence that cut a frame begun short (the firmware's params::kFrameTimeout)."""

    def __init__(self, protocol: Protocol) -> None:
        self.protocol = protocol
        self.buffer = b""  # the bytes from the candidate sync pair on, not yet a frame

    def feed(self, data: bytes) -> list[RawFrame]:
        """The frames completed by these bytes (and the ones before them), in order."""
        sync = self.protocol.sync
        self.buffer += data
        frames: list[RawFrame] = []
        while True:
            start = self.buffer.find(sync)
            if start < 0:
                # Junk; keep a last byte that may be the first of a sync pair.
                self.buffer = self.buffer[-1:] if self.buffer[-1:] == sync[:1] else b""
                return frames
            self.buffer = self.buffer[start:]
            if len(self.buffer) < HEADER:
                return frames
            code, length = self.buffer[2], self.buffer[3]
            if self.protocol.payload_length(code) != length:
                self.buffer = self.buffer[2:]  # an unknown type or a wrong length: hunt again after the pair
                continue
            end = HEADER + length + CRC
            if len(self.buffer) < end:
                return frames
            body = self.buffer[2:HEADER + length]
            (crc,) = struct.unpack("<H", self.buffer[HEADER + length:end])
            if self.protocol.crc16(body) == crc:
                frames.append(RawFrame(self.protocol.by_code[code].type, body[2:]))
                self.buffer = self.buffer[end:]
            else:
                self.buffer = self.buffer[2:]  # a bad CRC: the pair was not a frame's start

    def expire(self) -> list[RawFrame]:
        """The in-frame timeout: the frame begun is cut short; the frames in the bytes after its start."""
        if not self.buffer.startswith(self.protocol.sync[:1]):
            return []
        self.buffer = self.buffer[1:]
        return self.feed(b"")
