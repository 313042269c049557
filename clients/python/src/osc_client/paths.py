"""A stream's path: read from a CSV file, sampled at the stream's rate with the path's velocity."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

from .errors import ClientError
from .frames import Floats

PathRow = tuple[float, float, float, float, float, float, float]
"""t [s], x, y, z [m], roll, pitch, yaw [rad]."""


@dataclass(frozen=True)
class PathPoint:
    """One setpoint of a stream: where the wrist centre is to be, and how fast the path goes there."""

    position: Floats  # x, y, z [m]
    rpy: Floats  # roll, pitch, yaw [rad]
    velocity: Floats = (0.0,) * 6  # linear [m/s], then angular in the base frame [rad/s]


def read_stream_csv(path: str) -> tuple[list[PathRow], bool]:
    """The rows of a path file and whether it gives the orientation.

    The CSV that puma_experiment's scripts and oscctl read: ``t, x, y, z[, roll, pitch, yaw]`` in s,
    m and degrees (returned in radians; without them 0); a header row and ``#`` comments skipped; t
    from 0, increasing; every row with the same columns. A ClientError names the file and line.
    """
    try:
        with open(path) as f:
            lines = f.read().splitlines()
    except OSError as e:
        raise ClientError(f"{path}: cannot be read") from e
    rows: list[PathRow] = []
    columns = 0
    for n, line in enumerate(lines, 1):
        where = f"{path}:{n}: "
        text = line.strip(" \t\r")
        if not text or text.startswith("#"):
            continue
        try:
            v = [float(c) for c in text.split(",")]
        except ValueError:
            if not rows and columns == 0:
                columns = -1  # the header
                continue
            raise ClientError(where + "not a row of numbers") from None
        if len(v) not in (4, 7):
            raise ClientError(where + f"{len(v)} columns: t, x, y, z[, roll, pitch, yaw] needs 4 or 7")
        if columns > 0 and len(v) != columns:
            raise ClientError(where + f"every row needs the same columns ({columns})")
        columns = len(v)
        if not all(math.isfinite(x) for x in v):
            raise ClientError(where + "not a finite number")
        t, x, y, z = v[:4]
        roll, pitch, yaw = (math.radians(a) for a in v[4:]) if len(v) == 7 else (0.0, 0.0, 0.0)
        if not rows and t != 0:
            raise ClientError(where + "the path's time starts at 0")
        if rows and not t > rows[-1][0]:
            raise ClientError(where + "t must increase from row to row")
        rows.append((t, x, y, z, roll, pitch, yaw))
    if not rows:
        raise ClientError(f"{path}: no rows (t, x, y, z[, roll, pitch, yaw])")
    return rows, columns == 7


def angular_velocity(rpy: Sequence[float], rpy_rate: Sequence[float]) -> list[float]:
    """The base-frame angular velocity w = E(rpy) rpy_dot of R = Rz(yaw) Ry(pitch) Rx(roll).

    The firmware's osc::phi_rate_to_angular.
    """
    sb, cb = math.sin(rpy[1]), math.cos(rpy[1])
    sg, cg = math.sin(rpy[2]), math.cos(rpy[2])
    r = rpy_rate
    return [cg * cb * r[0] - sg * r[1], sg * cb * r[0] + cg * r[1], -sb * r[0] + r[2]]


def resample_path(rows: Sequence[PathRow], rate_hz: float) -> list[PathPoint]:
    """The path sampled every 1 / rate_hz s from t = 0, linearly between rows.

    Each point carries the path's velocity there: the segment's slope, linear and then angular in
    the base frame; zero at the end. The last point is the path's end (the C++ client's
    osc::client::resample_path).
    """
    points = []
    period, end = 1.0 / rate_hz, rows[-1][0]
    i, n = 1, 0
    while True:
        t = n * period
        last = t >= end - 1e-9
        while i < len(rows) and rows[i][0] < t:
            i += 1
        if last:
            points.append(PathPoint(rows[-1][1:4], rows[-1][4:7]))
            return points
        a, b = rows[i - 1], rows[i]
        dt = b[0] - a[0]
        f = (t - a[0]) / dt
        x = [a[c] + f * (b[c] - a[c]) for c in range(7)]
        rate = [(b[c] - a[c]) / dt for c in range(1, 7)]
        velocity = rate[:3] + angular_velocity(x[4:7], rate[3:])
        points.append(PathPoint(tuple(x[1:4]), tuple(x[4:7]), tuple(velocity)))
        n += 1
