"""Paths from the text form and from points: their length and shape from closed forms, their
heading, and one-line refusals of what is not a path."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin.control.path import figure8, parse_path, polyline, spline
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


def test_a_closed_spline_through_points_of_a_circle_is_that_circle():
    # twelve points on the unit circle: the periodic cubic spline through them departs from the
    # circle by about R (h / R)^4 / 384 with h the chord, well under a millimetre
    phi = np.linspace(0.0, 2 * math.pi, 12, endpoint=False)
    path = spline(np.column_stack((np.cos(phi), np.sin(phi))), closed=True)
    radius = np.hypot(path.pose[:, 0], path.pose[:, 1])
    assert np.max(np.abs(radius - 1.0)) < 5e-4
    assert path.travel == pytest.approx(2 * math.pi, rel=2e-4)  # (h / R)^4 / 384 = 1.9e-4
    assert path.closed and np.allclose(path.pose[-1, :2], path.pose[0, :2], atol=1e-9)
    # tangent heading: perpendicular to the radius, counter-clockwise
    tangent = np.column_stack((np.cos(path.pose[:, 2]), np.sin(path.pose[:, 2])))
    assert np.max(np.abs(np.sum(tangent * path.pose[:, :2], axis=1))) < 2e-3


def test_a_spline_passes_through_its_points_and_two_points_make_a_line():
    points = np.array([(0.0, 0.0), (1.0, 0.5), (2.0, -0.5), (3.0, 0.0)])
    path = spline(points)
    for p in points:  # each point within half a sample spacing of the curve's samples
        assert np.min(np.hypot(*(path.pose[:, :2] - p).T)) <= 1e-3
    line = spline([(0.0, 0.0), (3.0, 4.0)], heading="fixed")
    assert line.travel == pytest.approx(5.0, rel=1e-9)
    assert np.allclose(line.pose[:, 2], 0.0)


@pytest.mark.parametrize(
    ("given", "end"),
    [
        ((0.0, 3.0), 3.0),
        ((0.0, -3.0), -3.0),
        ((3.0, -3.0), 3.0 + (2 * math.pi - 6.0)),  # the shorter way: +0.28 rad, not -6 rad
        ((0.0, 4 * math.pi + 0.5), 0.5),  # whole turns are no turn
    ],
)
def test_headings_given_per_point_turn_the_shorter_way_along_each_segment(given, end):
    for build in (polyline, spline):
        path = build([(0.0, 0.0), (2.0, 0.0)], theta=given)
        assert path.pose[0, 2] == pytest.approx(given[0])
        assert path.pose[-1, 2] == pytest.approx(end)
        # evenly along the segment: halfway, half the turn
        middle = np.argmin(np.abs(path.pose[:, 0] - 1.0))
        assert path.pose[middle, 2] == pytest.approx((given[0] + end) / 2, abs=2e-3)


def test_a_polyline_with_headings_per_point_reaches_each_point_at_its_heading():
    points = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
    theta = [0.0, 1.0, 2.0, -1.0]
    path = polyline(points, theta=theta)
    for (x, y), th in zip(points, theta, strict=True):
        k = np.argmin(np.hypot(path.pose[:, 0] - x, path.pose[:, 1] - y))
        assert math.remainder(path.pose[k, 2] - th, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
    assert path.travel == pytest.approx(3.0, rel=1e-9)  # no turn in place: the heading is given


def test_a_self_crossing_polyline_is_a_path():
    # a bow tie crosses itself at (0.5, 0.5): a path may (the figure-eight does)
    path = polyline([(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)], blend=0.1)
    assert path.travel < 2 * math.sqrt(2) + 1.0


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: polyline([(0, 0), (1, 0)], theta=[0.0]), r"1 headings for 2 points"),
        (lambda: polyline([(0, 0), (1, 0)], theta=[0.0, float("nan")]), r"heading of point 1 is not finite"),
        (lambda: polyline([(0, 0), (1, 0)], theta=[0.0, 1.0], heading="fixed"), r"headings are given per point"),
        (lambda: spline([(0, 0), (1, 0), (1, 0)]), r"points 1 and 2 are the same"),
        (lambda: spline([(0, 0), (1, 0), (0, 0)], closed=True), r"points 2 and 0 are the same"),
        (lambda: spline([(0, 0), (1e308, 0), (-1e308, 0)]), r"point 1 is more than 1e\+07 m from the origin"),
        (lambda: polyline([(0, 0), (9e6, 0), (-9e6, 0)]), r"too long"),
        (lambda: spline([(0, 0), (2000, 0)]), r"2000 m is too long"),
        (lambda: polyline([(0, 0), (1, 0)], theta=[1e300, 0.0]), r"heading of point 0 is beyond 10000 rad"),
        (lambda: parse_path("circle 1", heading=1e300), r"heading must be an angle within 10000 rad"),
    ],
)
def test_points_that_make_no_path_are_refused_in_one_line(call, message):
    with pytest.raises(InputError, match=message) as info:
        call()
    assert "\n" not in str(info.value)
