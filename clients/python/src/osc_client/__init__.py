"""A client of the controller's command protocol (docs/protocol.md; docs/motion.md, "Clients").

Pure Python 3 with pyserial (Debian's ``python3-serial``). The frame layouts and the names of every
code are not typed here: they come from ``osc_protocol.json``, which the firmware's own declarations
write (``osc_protocol --client``; ``scripts/client_protocol.py``). The package's copy is the default
arm's (the PUMA 560); for a board built for another arm give its build's file
(``BUILD/clients/osc_protocol.json``) as ``Protocol(path)``, ``--protocol FILE`` or ``$OSC_PROTOCOL``.

As a module::

    from osc_client import Client
    c = Client("/dev/pts/7")
    c.wait_answer(c.enable())
    print(c.wait_done(c.move_to((0, 0.02, 0), relative=True)).text())   # done, aborted: stop_command, ...

As a program (``osc-client``, or ``python3 -m osc_client``), oscctl's verbs: see ``osc_client.cli``.

The parts, in the order a frame meets them:

- ``protocol``: the declaration (``Protocol``): frame types, layouts, flags, names; encode, decode, CRC
- ``frames``: each frame type as a dataclass (``Command``, ``Answer``, ``State``, ``Identify`` ...)
- ``parser``: frames out of a byte stream, resynchronising after a bad one (``Parser``)
- ``transport``: the byte stream (``Transport``; ``SerialTransport``, a serial device or pseudo-terminal)
- ``client``: commands and their outcomes (``Client``, ``Outcome``, ``Status``)
- ``paths``: a stream's CSV path and its setpoints (``read_stream_csv``, ``resample_path``)
- ``record``: state frames as CSV rows (``state_columns``, ``csv_row``, ``CsvRecorder``) and named signals
  (``parse_signal``: ``x[0]``, ``error`` ...; ``Traces``, their values over time)
- ``capture``: the board's capture, its oscilloscope (``Oscilloscope``: arm, trigger, status, read;
  ``CaptureResult``, a capture's ticks and values; ``parse_channel``: ``residual[1]``, ``error[0]`` ...)
- ``plot``: signals and captures drawn with matplotlib, a PNG or a live window (imported by
  ``osc_client.plot`` only: matplotlib is needed by it alone)
- ``text``, ``cli``: oscctl's output and verbs
"""
from .capture import (CaptureChannel, CaptureRefused, CaptureResult, Oscilloscope, capture_signals_text,
                      parse_channel, parse_channels)
from .client import Client, Outcome, Status
from .errors import ClientError
from .frames import (Actuator, Answer, Capture, CaptureData, Command, Frame, FrameType, Identify, IdentifyOffset,
                     IdentifyPayload, Param, ParamAnswer, Sensor, Setpoint, SetpointVelocity, State, Trace)
from .parser import Parser, RawFrame
from .paths import PathPoint, angular_velocity, read_stream_csv, resample_path
from .protocol import PROTOCOL_JSON, CaptureSignal, CaptureSpec, NameList, Parameter, Protocol, crc16, protocol_path
from .record import (Column, CsvRecorder, Signal, SignalKind, Traces, csv_header, csv_row, parse_signal,
                     parse_signals, signal_names, state_columns, state_row)
from .transport import SerialTransport, Transport

__all__ = [
    "Actuator", "Answer", "Capture", "CaptureChannel", "CaptureData", "CaptureRefused", "CaptureResult",
    "CaptureSignal", "CaptureSpec", "Client", "ClientError", "Column", "Command", "CsvRecorder", "Frame", "FrameType",
    "Identify", "IdentifyOffset", "IdentifyPayload", "NameList", "Oscilloscope", "Outcome", "PROTOCOL_JSON", "Param",
    "ParamAnswer", "Parameter", "Parser", "PathPoint", "Protocol", "RawFrame", "Sensor", "SerialTransport", "Setpoint",
    "SetpointVelocity", "Signal", "SignalKind", "State", "Status", "Trace", "Traces", "Transport", "angular_velocity",
    "capture_signals_text", "crc16", "csv_header", "csv_row", "parse_channel", "parse_channels", "parse_signal",
    "parse_signals", "protocol_path", "read_stream_csv", "resample_path", "signal_names", "state_columns", "state_row"
]
