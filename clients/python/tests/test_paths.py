"""A stream's path: the CSV file and its setpoints."""
from __future__ import annotations

import math
from pathlib import Path

import pytest

from osc_client import ClientError, angular_velocity, read_stream_csv, resample_path


def csv(tmp_path: Path, text: str) -> str:
    path = tmp_path / "path.csv"
    path.write_text(text)
    return str(path)


def test_reads_header_comments_and_degrees(tmp_path: Path) -> None:
    rows, has_rpy = read_stream_csv(csv(tmp_path, "t, x, y, z, r, p, y\n# a comment\n\n0, 0, 0, 0, 0, 0, 0\n"
                                                  "1, 0.1, 0, 0, 90, 0, -180\n"))
    assert has_rpy and len(rows) == 2
    assert rows[1] == pytest.approx((1, 0.1, 0, 0, math.pi / 2, 0, -math.pi))


def test_four_columns_have_no_orientation(tmp_path: Path) -> None:
    rows, has_rpy = read_stream_csv(csv(tmp_path, "0,0,0,0\n0.5,0,0.01,0\n"))
    assert not has_rpy and rows[1][4:] == (0.0, 0.0, 0.0)


@pytest.mark.parametrize("text, message", [
    ("t,x,y,z\n0,0,0,0\n1,0,x,0\n", r":3: not a row of numbers"),
    ("0,0,0\n", r":1: 3 columns"),
    ("0,0,0,0\n1,0,0,0,0,0,0\n", r":2: every row needs the same columns \(4\)"),
    ("0,0,0,nan\n", r":1: not a finite number"),
    ("1,0,0,0\n", r":1: the path's time starts at 0"),
    ("0,0,0,0\n0,0,0,0\n", r":2: t must increase"),
    ("# nothing\n", r"no rows"),
])
def test_bad_files_name_the_line(tmp_path: Path, text: str, message: str) -> None:
    with pytest.raises(ClientError, match=message):
        read_stream_csv(csv(tmp_path, text))


def test_a_missing_file(tmp_path: Path) -> None:
    with pytest.raises(ClientError, match="cannot be read"):
        read_stream_csv(str(tmp_path / "none.csv"))


def test_resample_with_velocity(tmp_path: Path) -> None:
    rows, _ = read_stream_csv(csv(tmp_path, "0,0,0,0\n0.6,0,0.01,0\n1.2,0,0.01,0.01\n"))
    points = resample_path(rows, 10)
    assert len(points) == 13  # t = 0, 0.1 .. 1.2
    assert points[3].position == pytest.approx((0, 0.005, 0))
    assert points[3].velocity == pytest.approx((0, 0.01 / 0.6, 0, 0, 0, 0))
    assert points[9].velocity == pytest.approx((0, 0, 0.01 / 0.6, 0, 0, 0))
    assert points[-1].position == pytest.approx((0, 0.01, 0.01)) and points[-1].velocity == (0.0,) * 6


def test_angular_velocity() -> None:
    assert angular_velocity([0, 0, 0], [1, 2, 3]) == pytest.approx([1, 2, 3])
    # Yaw a quarter turn: a roll rate turns about the base's y axis.
    assert angular_velocity([0, 0, math.pi / 2], [1, 0, 0]) == pytest.approx([0, 1, 0])
