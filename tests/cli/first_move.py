#!/usr/bin/env python3
"""The first move after a power-on, over the command protocol (issue 57, persistence): enable, then
test_motion_sim's move (0.10, -0.08, 0.05 m from where the arm holds, 0.3 rad of yaw, at the move maxima), and
its largest position error |x_d - x| [mm] over the state frames (50 Hz) while it runs, as the board reports it.

usage: first_move.py PORT   (PYTHONPATH: clients/python/src)
Prints "first move: tracking X.XXX mm"; exit 0 when the move ended done, 1 otherwise.
"""
from __future__ import annotations

import math
import sys

from osc_client import Client, State
from osc_client.client import Status


def main(port: str) -> int:
    c = Client(port)
    worst = 0.0
    moving = False

    def on_state(s: State) -> None:
        nonlocal worst
        if moving and len(s.x_d) >= 3 and len(s.x) >= 3:
            worst = max(worst, math.dist(s.x_d[:3], s.x[:3]))

    c.on_state = on_state
    enabled = c.wait_done(c.enable(), 30)
    if enabled.status != Status.DONE:
        print(f"enable: {enabled.text()}")
        return 1
    c.pump(0.3)
    moving = True
    done = c.wait_done(c.move_to((0.10, -0.08, 0.05), rpy=(0.0, 0.0, 0.3), relative=True), 60)
    moving = False
    print(f"move: {done.text()}")
    print(f"first move: tracking {worst * 1e3:.3f} mm")
    c.close()
    return 0 if done.status == Status.DONE else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
