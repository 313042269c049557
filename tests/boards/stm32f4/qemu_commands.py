#!/usr/bin/env python3
"""The STM32F4 board's command link end to end (ctest stm32f4_qemu_commands).

usage: qemu_commands.py CLIENT_SRC QEMU_COMMAND...

Starts QEMU_COMMAND (qemu-system-arm -M netduinoplus2 ... -kernel stm32f4_qemu_link.elf) with the
board's USART2 on a pseudo-terminal (-serial pty: QEMU names it on its standard output, "char device
redirected to /dev/pts/N"), and drives it with the project's Python client (the package osc_client,
from CLIENT_SRC: clients/python/src), as a user would drive the board over a serial adapter:
  1. a state frame says disabled (the board starts disabled);
  2. enable is accepted, and the state becomes holding;
  3. a move_to far outside the workspace (2 m along x from where the arm holds) is refused
     out_of_workspace (the board's path check, in its main loop);
  4. stop is accepted (holding: nothing to stop) and done;
  5. disable is accepted, and the state becomes disabled;
  6. the parameters: a set of k_s while disabled is accepted and reads back, refused torque_on while
     enabled; save, reset and load bring it back (in RAM here: QEMU models no flash controller);
  7. an identify run, followed by the board's main loop (osc/link/identify_port.hpp): the still robot
     declared at the start pose, the wrist's gains lowered so that the run passes the sampled loop's
     check there (at the paper's gains it is refused unstable_loop, docs/adaptation.md), accepted;
     the encoders do not move in QEMU, so a monitor stops it (aborted), and the board sends its
     identify frame, status aborted, with the samples its main loop took and none lost, and its identify_offset
     frame.
The encoders do not move in QEMU, so no motion runs to its end. No timing is asserted: every wait is generous
(the machine may be busy). Prints one line per step; exit 0 when all pass, 1 otherwise.
"""
import re
import subprocess
import sys
import threading
import time

TIMEOUT = 60.0  # seconds for each answer or state: QEMU on a loaded machine


def find_pty(proc, deadline):
    """The pseudo-terminal QEMU names on its standard output; the rest of it is echoed by a thread."""
    lines = []
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        lines.append(line)
        m = re.search(r"char device redirected to (/dev/pts/\d+)", line)
        if m:
            threading.Thread(target=lambda: [sys.stdout.write(x) for x in proc.stdout], daemon=True).start()
            return m.group(1)
    raise RuntimeError("QEMU named no pseudo-terminal: " + "".join(lines))


def wait_state(c, name, timeout=TIMEOUT):
    """The first state frame whose motion state is `name` (None after the timeout)."""
    from osc_client import NameList  # from CLIENT_SRC (main)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        s = c.state(timeout=deadline - time.monotonic())
        if s is not None and c.protocol.name_of(NameList.MOTION_STATES, s.state) == name:
            return s
    return None


def run(c):
    from osc_client import NameList, Status  # from CLIENT_SRC (main)
    ok = True

    def check(what, good, detail=""):
        nonlocal ok
        ok &= bool(good)
        print(f"{'ok  ' if good else 'FAIL'} {what}{': ' + detail if detail else ''}", flush=True)

    def motion_state(s):
        return c.protocol.name_of(NameList.MOTION_STATES, s.state) if s else "no state frame"

    s = c.state(timeout=TIMEOUT)
    check("boots disabled", motion_state(s) == "disabled", motion_state(s))
    o = c.wait_answer(c.enable(), TIMEOUT)
    check("enable accepted", o.status == Status.ACCEPTED, o.text())
    check("holding after enable", wait_state(c, "holding") is not None)
    o = c.wait_answer(c.move_to((2.0, 0.0, 0.0), relative=True), TIMEOUT)
    check("a move_to outside the workspace refused out_of_workspace",
          o.status == Status.REFUSED and o.reason == "out_of_workspace", o.text())
    o = c.wait_done(c.stop(), TIMEOUT)
    check("stop accepted and done (holding)", o.status == Status.DONE, o.text())
    o = c.wait_answer(c.disable(), TIMEOUT)
    check("disable accepted", o.status == Status.ACCEPTED, o.text())
    s = wait_state(c, "disabled")
    check("disabled after disable", s is not None)
    if s is not None:
        check("no fault", s.faults == 0, c.protocol.fault_names(s.faults))
        check("no setpoint dropped (keep-alive frames are no setpoints)", s.dropped == 0, str(s.dropped))
    ks = c.protocol.parameter("ks").index
    a = c.param("set", ks, 1, 80.0, timeout=TIMEOUT)
    check("param set ks[1] = 80 accepted", a.status == 0 and a.value == 80.0, str(a))
    names = [c.param(op, timeout=TIMEOUT).status for op in ("save", "reset")]
    check("save and reset ok", names == [0, 0], str(names))
    check("reset: ks[1] back to 97", c.param("get", ks, 1, timeout=TIMEOUT).value == 97.0)
    check("load ok", c.param("load", timeout=TIMEOUT).status == 0)
    check("load: ks[1] is 80 again", c.param("get", ks, 1, timeout=TIMEOUT).value == 80.0)
    o = c.wait_answer(c.enable(), TIMEOUT)
    check("enable accepted", o.status == Status.ACCEPTED, o.text())
    wait_state(c, "holding")
    a = c.param("set", ks, 1, 90.0, timeout=TIMEOUT)
    check("param set while enabled refused torque_on",
          c.protocol.name_of(NameList.PARAM_STATUSES, a.status) == "torque_on" and a.value == 80.0, str(a))
    o = c.wait_answer(c.disable(), TIMEOUT)
    check("disable accepted", o.status == Status.ACCEPTED, o.text())
    identify_aborted(c, check)  # its failures through check
    return ok


def identify_aborted(c, check):
    """Step 7: an identify run on the still robot, aborted by a monitor, and its identify frame."""
    from osc_client import NameList, Status  # from CLIENT_SRC (main)
    o = c.wait_done(c.declare_pose("start"), TIMEOUT)
    check("declare_pose start done", o.status == Status.DONE, o.text())
    for name, value in (("knd", 10.0), ("ks", 10.0), ("ki", 1000.0)):  # the wrist's: the roll axis is light
        index = c.protocol.parameter(name).index
        for e in (3, 4, 5):
            a = c.param("set", index, e, value, timeout=TIMEOUT)
            check(f"param set {name}[{e}] = {value:g}", a.status == 0, str(a))
    o = c.wait_answer(c.enable(), TIMEOUT)
    check("enable accepted", o.status == Status.ACCEPTED, o.text())
    check("holding after enable", wait_state(c, "holding") is not None)
    cid = c.identify()
    o = c.wait_answer(cid, TIMEOUT)
    check("identify accepted (prepared in the main loop: four scales' checks at most)",
          o.status == Status.ACCEPTED, o.text())
    o = c.wait_done(cid, TIMEOUT)
    check("the run aborted: the encoders do not move", o.status == Status.ABORTED, o.text())
    f = c.wait_identify(cid, TIMEOUT)
    check("the identify frame came", f is not None)
    if f is None:
        return
    status = c.protocol.name_of(NameList.IDENTIFY_STATUSES, f.status)
    check("its status aborted", status == "aborted", status)
    check("the main loop took the run's samples, none lost", f.samples > 0 and f.lost == 0,
          f"{f.samples} samples, {f.lost} lost")
    fo = c.wait_identify_offset(cid, TIMEOUT)
    check("the identify_offset frame came right after it, status aborted",
          fo is not None and c.protocol.name_of(NameList.IDENTIFY_STATUSES, fo.status) == "aborted", str(fo))


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    sys.path.insert(0, argv[0])
    import osc_client
    cmd = argv[1:] + ["-serial", "pty"] if "-kernel" not in argv[1:] else None
    if cmd is None:  # the serial port before -kernel, as the other QEMU tests give theirs
        k = argv.index("-kernel")
        cmd = argv[1:k] + ["-serial", "pty"] + argv[k:]
    proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True)
    try:
        pty = find_pty(proc, time.monotonic() + TIMEOUT)
        print(f"board on {pty}", flush=True)
        c = osc_client.Client(pty, 460800, keepalive=0.1)  # keep-alive frames too: taken as link activity
        ok = run(c)
        c.close()
    except (RuntimeError, osc_client.ClientError) as e:
        print(f"FAIL {e}", flush=True)
        ok = False
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
    print("stm32f4_qemu_commands: " + ("pass" if ok else "FAIL"), flush=True)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
