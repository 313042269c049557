"""The command line's output and exit status, against byte streams recorded from the virtual board
(tests/data, record_streams.py), and its named errors."""
from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from osc_client import Client, Protocol
from osc_client.cli import main
from replay import Recording, ReplayTransport, recordings

SRC = str(Path(__file__).resolve().parent.parent / "src")


def replay(r: Recording, argv: list[str] | None = None) -> tuple[int, ReplayTransport]:
    transport = ReplayTransport(list(r.board))

    def connect(port: str, baud: int, protocol: Protocol, keepalive: float) -> Client:
        assert port == "/dev/recorded"
        return Client(transport, protocol=protocol, keepalive=keepalive, first_id=r.first_id)

    return main(["--port", "/dev/recorded"] + (r.argv if argv is None else argv), connect=connect), transport


def test_the_recordings_cover_every_exit_status_and_outcome() -> None:
    runs = recordings()
    assert {r.exit for r in runs} == {0, 1}
    out = "".join(r.stdout for r in runs)
    for line in ("state: disabled", "refused: not_enabled", "accepted", "done", "aborted 5000: stop_command",
                 "ks[0] = 97", "refused: out_of_range", "refused: pots_disagree"):
        assert line in out


@pytest.mark.parametrize("r", recordings(), ids=[r.name for r in recordings()])
def test_replayed_run_prints_and_exits_as_recorded(r: Recording, capsys: pytest.CaptureFixture[str]) -> None:
    rc, transport = replay(r)
    assert capsys.readouterr().out == r.stdout
    assert rc == r.exit
    if r.first_write:
        assert transport.written[0] == r.first_write  # the same command frame, byte for byte
    assert transport.closed


def test_no_answer_is_a_timeout_exit_1(capsys: pytest.CaptureFixture[str]) -> None:
    rc, transport = replay(Recording("silent", [], 1, [], b"", "", 0), ["--timeout", "0.3", "enable"])
    assert (rc, capsys.readouterr().out) == (1, "timeout\n")
    assert len(transport.written) >= 1


def test_no_state_frame_exit_1(capsys: pytest.CaptureFixture[str]) -> None:
    rc, _ = replay(Recording("silent", [], 1, [], b"", "", 0), ["--timeout", "0.2", "state"])
    captured = capsys.readouterr()
    assert rc == 1 and "no state frame within the time" in captured.err and captured.out == ""


def test_a_corrupted_recording_changes_the_outcome(capsys: pytest.CaptureFixture[str]) -> None:
    """The replay is a test: a bad CRC on the one answer leaves the command without one."""
    (r,) = [r for r in recordings() if r.name == "enable"]
    bad = [bytes(c[:-1]) + bytes([c[-1] ^ 1]) for c in r.board]
    rc, _ = replay(Recording(r.name, r.argv, r.first_id, bad, b"", "", 0), ["--timeout", "0.3", "enable"])
    assert (rc, capsys.readouterr().out) == (1, "timeout\n")


@pytest.mark.parametrize("argv, message", [
    (["--port", "/dev/null", "fly"], "invalid choice: 'fly'"),
    (["--port", "/dev/null", "move", "1", "2"], "the following arguments are required"),
    (["--port", "/dev/null", "move", "1", "2", "nan"], "must be finite numbers"),
    (["--port", "/dev/null", "--baud", "10", "state"], "--baud 10: 50 to 4000000"),
    (["--port", "/dev/null", "--keepalive", "1", "state"], "must be from 0 \\(none\\) to 0.4"),
    (["--port", "/dev/null", "param", "set", "nosuch", "1"], "param nosuch: no such parameter \\(knd, k, "),
    (["--port", "/dev/null", "param", "set", "ks", "1"], "param set ks: 6 values \\(one per element"),
    (["--port", "/dev/null", "param", "get", "k_ad", "--element", "1"], "param k_ad --element 1: it has 1 element"),
    (["--port", "/dev/null", "param", "save", "ks"], "param save takes no name"),
    (["--port", "/dev/null", "enable", "--apply"], "unrecognized arguments: --apply"),  # identify's flag only
    (["--port", "/dev/null", "param", "list", "--apply"], "unrecognized arguments: --apply"),
    (["--port", "/dev/null", "--apply", "identify"], "unrecognized arguments: --apply"),
])
def test_bad_command_line_exits_2(argv: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as e:
        main(argv)
    assert e.value.code == 2
    assert re.search(message, capsys.readouterr().err)


def test_param_values_after_options_are_taken(capsys: pytest.CaptureFixture[str]) -> None:
    """``param set k --element 0 2500``: the value after the option is the value (the recording's)."""
    (r,) = [r for r in recordings() if r.name == "param_refused"]
    assert r.argv[-4:] == ["k", "--element", "0", "2500"]
    rc, transport = replay(r)
    assert rc == 1 and capsys.readouterr().out == "refused: out_of_range\n"
    assert transport.written[0] == r.first_write  # a param frame setting element 0 to 2500


@pytest.mark.parametrize("setup, argv, message", [
    (None, ["--port", "{tmp}/none", "state"], "osc_client: {tmp}/none: No such file or directory"),
    ("file", ["--port", "{tmp}/f.csv", "state"], "osc_client: {tmp}/f.csv: not a serial device or terminal"),
    ("file", ["--port", "/dev/null", "stream", "{tmp}/f.csv", "--rate", "10"], "osc_client: {tmp}/f.csv:3: not a row"),
    (None, ["--protocol", "{tmp}/none.json", "--port", "/dev/null", "state"],
     "osc_client: {tmp}/none.json: cannot read the protocol's description"),
    (None, ["--protocol", "", "--port", "/dev/null", "state"], "osc_client: the protocol's description: an empty"),
])
def test_bad_port_or_file_exits_2(tmp_path: Path, setup: str | None, argv: list[str], message: str,
                                  capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "f.csv").write_text("t,x,y,z\n0,0,0,0\n1,0,x,0\n")
    assert main([a.replace("{tmp}", str(tmp_path)) for a in argv]) == 2
    assert message.replace("{tmp}", str(tmp_path)) in capsys.readouterr().err


def test_python_m_osc_client_help(tmp_path: Path) -> None:
    """The program as ``python3 -m osc_client``, from another directory."""
    env = dict(os.environ, PYTHONPATH=SRC)
    run = subprocess.run([sys.executable, "-m", "osc_client", "--help"], cwd=tmp_path, env=env, capture_output=True,
                         text=True, check=False)
    assert run.returncode == 0 and "usage: osc-client" in run.stdout and "declare_pose" in run.stdout
    run = subprocess.run([sys.executable, "-m", "osc_client", "--port", "/dev/null", "fly"], cwd=tmp_path, env=env,
                         capture_output=True, text=True, check=False)
    assert run.returncode == 2 and "invalid choice: 'fly'" in run.stderr
