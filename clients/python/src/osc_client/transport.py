"""Byte streams a client talks over: a serial device or a pseudo-terminal.

The protocol runs on any byte stream. :class:`Transport` is what the client needs of one; the
package has :class:`SerialTransport`, a serial device or pseudo-terminal (a board's port, a USB
serial adapter, the virtual board ``osc_sim --pty``) through pyserial (Debian's ``python3-serial``),
in raw mode at any baud rate. Another stream (a socket, a recording in the tests) is any object with
the three methods.
"""
from __future__ import annotations

import os
import select
from typing import Any, Protocol

from .errors import ClientError


class Transport(Protocol):
    """A byte stream to and from a controller."""

    def read(self, timeout: float) -> bytes:
        """The bytes that arrived, waiting up to ``timeout`` seconds for some (b"" when none did)."""

    def write(self, data: bytes) -> None:
        """Sends all of ``data``; a ClientError when the stream has failed."""

    def close(self) -> None:
        """Closes the stream."""


class SerialTransport:
    """A serial device or pseudo-terminal, raw, at ``baud`` (which a pseudo-terminal ignores)."""

    READ_SIZE = 4096

    def __init__(self, port: str, baud: int = 115200) -> None:
        try:
            import serial  # pyserial
        except ImportError as e:
            raise ClientError("pyserial is missing (Debian: apt-get install python3-serial)") from e
        self._serial_error: type[Exception] = serial.SerialException
        try:
            fd = os.open(port, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        except OSError as e:
            raise ClientError(f"{port}: {e.strerror}") from e
        tty = os.isatty(fd)
        os.close(fd)
        if not tty:
            raise ClientError(f"{port}: not a serial device or terminal")
        try:
            self._serial: Any = serial.Serial(port, baud, timeout=0)
            self._serial.reset_input_buffer()  # an earlier client's unread bytes
        except (serial.SerialException, ValueError, OSError) as e:
            raise ClientError(f"{port}: {e}") from e
        self.port = port

    def read(self, timeout: float) -> bytes:
        try:
            if not select.select([self._serial.fileno()], [], [], timeout)[0]:
                return b""
            return bytes(self._serial.read(self.READ_SIZE))
        except (self._serial_error, OSError) as e:
            raise ClientError(f"{self.port}: hung up (the board or the simulator has gone)") from e

    def write(self, data: bytes) -> None:
        try:
            self._serial.write(data)
        except (self._serial_error, OSError) as e:
            raise ClientError(f"{self.port}: {e}") from e

    def close(self) -> None:
        self._serial.close()
