#!/usr/bin/env python3
"""Records the byte streams of test_cli.py from the virtual board (run by hand, not by the tests).

usage: PYTHONPATH=clients/python/src python3 clients/python/tests/record_streams.py OSC_SIM

Starts ``OSC_SIM --pty --speed 4 --scalar float --no-link-watch`` and runs the command line through a
sequence (state, a refusal, enable, a move done, a stop aborting a move, the parameters, a pose
refused, disable), each run's board bytes, first write, output and exit status written to
tests/data/NAME.json. Commit the files the run rewrites with the change that needed them.
"""
from __future__ import annotations

import contextlib
import io
import subprocess
import sys

from replay import DATA, Recording, RecordingTransport

from osc_client import Client, Protocol, SerialTransport
from osc_client.cli import main

RUNS = [  # name, arguments after --port PORT (None: a set-up step, not recorded)
    ("state_disabled", ["state"]),
    ("move_refused", ["move", "0", "0.02", "0", "--relative"]),
    ("enable", ["enable"]),
    ("move_done", ["move", "0", "0.02", "0", "--relative"]),
    (None, ["move", "0", "0.03", "0", "--relative", "--v", "0.005", "--no-wait"]),
    ("stop_aborts_the_move", ["stop"]),
    ("param_get", ["param", "get", "ks", "--element", "0"]),
    ("param_refused", ["param", "set", "k", "--element", "0", "2500"]),
    ("disable", ["disable"]),
    ("declare_pose_refused", ["declare_pose", "zero"]),
]


def record(port: str, name: str | None, args: list[str], first_id: int) -> None:
    transports: list[RecordingTransport] = []

    def connect(port: str, baud: int, protocol: Protocol, keepalive: float) -> Client:
        transports.append(RecordingTransport(SerialTransport(port, baud)))
        return Client(transports[-1], protocol=protocol, keepalive=keepalive, first_id=first_id)

    argv = ["--timeout", "30"] + args
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        rc = main(["--port", port] + argv, connect=connect)
    print(f"{name}: exit {rc}\n{out.getvalue()}", end="")
    if name is not None:
        t = transports[0]
        first_write = t.written[0] if t.written else b""
        Recording(name, argv, first_id, t.read_chunks, first_write, out.getvalue(), rc).save(DATA / f"{name}.json")


def run(sim: str) -> None:
    board = subprocess.Popen([sim, "--pty", "--speed", "4", "--scalar", "float", "--no-link-watch"],
                             stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        assert board.stdout is not None
        port = board.stdout.readline().removeprefix("pty: ").strip()
        for n, (name, args) in enumerate(RUNS):
            record(port, name, args, 1000 * (n + 1))
    finally:
        board.terminate()
        board.wait(30)


if __name__ == "__main__":
    run(sys.argv[1])
