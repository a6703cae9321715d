"""Paths from the text form and from points: their length and shape from closed forms, their
heading, and one-line refusals of what is not a path."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin.control.path import figure8, parse_path, polyline
from omnikin.errors import InputError


@pytest.mark.parametrize(
    ("text", "length"),
    [
        ("circle 1", 2 * math.pi),
        ("circle 0.25", 0.5 * math.pi),
        # starting and ending at rest in one corner: the other three are cut by quarter arcs
        ("square 2 0.5", 4 * 2 - 3 * 2 * 0.5 + 3 * (math.pi / 2) * 0.5),
    ],
)
def test_a_built_in_path_has_the_length_of_its_closed_form(text, length):
    path = parse_path(text)
    assert path.travel == pytest.approx(length, rel=1e-5)
    assert np.allclose(path.pose[0], 0.0) and np.allclose(path.pose[-1, :2], 0.0, atol=1e-9)


def test_a_square_stopped_at_its_corners_turns_in_place_there():
    path = parse_path("square 1")
    assert path.travel == pytest.approx(4.0, rel=1e-9)
    # heading along each leg: 0, 90, 180, 270 deg, a stop at each corner
    corners = np.flatnonzero(path.stops)
    assert len(corners) == 2 + 2 * 3  # start, end, and arriving at / leaving each of three inner corners
    assert np.degrees(path.pose[-1, 2]) == pytest.approx(270.0)


def test_the_figure_eight_starts_along_x_and_crosses_itself_at_the_origin():
    path = figure8(1.0, heading="tangent")
    assert path.pose[0, 2] == pytest.approx(0.0, abs=1e-6)
    middle = len(path.s) // 2
    assert np.hypot(*path.pose[middle, :2]) < 2e-3
    # Gerono's lemniscate of size a: the loops reach a from the crossing (a point at phi = pi/2)
    assert np.max(np.hypot(path.pose[:, 0], path.pose[:, 1])) == pytest.approx(1.0, rel=1e-4)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("spiral 2", "unknown path 'spiral 2'"),
        ("", "unknown path ''"),
        ("circle", "expected 'circle RADIUS'"),
        ("circle 1 2", "expected 'circle RADIUS'"),
        ("circle nan", "RADIUS"),
        ("circle -1", "circle radius must be in"),
        ("circle 1e9", "circle radius must be in"),
        ("square 1 x", "BLEND"),
    ],
)
def test_a_bad_path_text_is_refused_in_one_line(text, message):
    with pytest.raises(InputError, match=message) as err:
        parse_path(text)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize(
    ("points", "message"),
    [
        ([[0, 0]], "does not go anywhere|fewer than two"),
        ([[0, 0], [0, 0], [1, 0]], "points 0 and 1 are the same"),
        ([[0, 0], [float("nan"), 1]], "point 1 is not finite"),
        ([[0, 0], [1e7, 0]], "too long"),
        ([[0, 0, 0, 0]], "expected rows of x, y"),
    ],
)
def test_points_that_are_not_a_path_are_refused_in_one_line(points, message):
    with pytest.raises(InputError, match=message):
        polyline(points)
