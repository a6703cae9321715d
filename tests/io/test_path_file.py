"""Path files (CSV and YAML waypoints) and the path argument that takes a file or a built-in path:
lengths from closed forms, closing and headings as written, one-line refusals naming the file and
the line or waypoint, bounded work on huge files."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin.errors import InputError, PathFileError
from omnikin.io import path_file
from omnikin.io.path_file import load_path, read_path_file


def write(tmp_path, name: str, text: str):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_a_csv_square_that_ends_where_it_starts_is_closed(tmp_path):
    f = write(tmp_path, "square.csv", "x,y\n0,0\n2,0\n2,2\n0,2\n0,0\n")
    path = read_path_file(f)
    assert path.closed and path.name == "square.csv"
    assert path.travel == pytest.approx(8.0, rel=1e-9)
    # blended: three corners cut by quarter arcs of 0.5 m (start and end at rest in the first)
    blended = read_path_file(f, blend=0.5)
    assert blended.travel == pytest.approx(8.0 - 3 * 2 * 0.5 + 3 * (math.pi / 2) * 0.5, rel=1e-5)


def test_an_open_csv_path_keeps_its_ends_and_reads_columns_by_name(tmp_path):
    f = write(tmp_path, "p.csv", "# a comment\ntheta,y,x\n0.5,0,0\n1.5,0,3\n")
    path = read_path_file(f)
    assert not path.closed
    assert path.pose[0] == pytest.approx([0.0, 0.0, 0.5])
    assert path.pose[-1] == pytest.approx([3.0, 0.0, 1.5])


def test_yaml_waypoints_as_lists_or_mappings(tmp_path):
    text = "closed: true\nwaypoints:\n  - [0, 0]\n  - {x: 1, y: 0}\n  - [1, 1]\n"
    path = read_path_file(write(tmp_path, "tri.yaml", text))
    assert path.closed
    assert path.travel == pytest.approx(2.0 + math.sqrt(2.0), rel=1e-9)
    smooth = read_path_file(write(tmp_path, "tri.yml", text), smooth=True)
    assert smooth.closed and smooth.travel > path.travel * 0.9


def test_the_heading_mode_applies_to_waypoints_without_theta(tmp_path):
    f = write(tmp_path, "l.csv", "x,y\n0,0\n0,1\n")
    assert read_path_file(f).pose[0, 2] == pytest.approx(math.pi / 2)  # tangent by default
    assert read_path_file(f, heading="fixed").pose[-1, 2] == pytest.approx(0.0)
    assert read_path_file(f, heading=0.3).pose[-1, 2] == pytest.approx(0.3)


def test_the_path_argument_is_a_file_or_a_built_in_path(tmp_path):
    f = write(tmp_path, "l.csv", "x,y\n0,0\n1,0\n")
    assert load_path(str(f)).travel == pytest.approx(1.0)
    assert load_path(f).travel == pytest.approx(1.0)
    assert load_path("circle 1").travel == pytest.approx(2 * math.pi, rel=1e-5)
    with pytest.raises(InputError, match=r"blend is for path files"):
        load_path("circle 1", blend=0.2)
    with pytest.raises(PathFileError, match=r"no such file"):
        load_path(str(tmp_path / "missing.csv"))


@pytest.mark.parametrize(
    ("name", "text", "message"),
    [
        ("a.csv", "", r"a.csv: empty"),
        ("a.csv", "x,z\n0,0\n", r"missing column\(s\) \['y'\]"),
        ("a.csv", "x,y,x\n0,0,0\n", r"duplicate column"),
        ("a.csv", "x,y\n0,0\n", r"1 waypoint\(s\); a path needs two or more"),
        ("a.csv", "x,y\n0,0\nnan,1\n", r"a.csv: line 3, column 'x': non-finite"),
        ("a.csv", "x,y\n0,0\n1,inf\n", r"a.csv: line 3, column 'y': non-finite"),
        ("a.csv", "x,y\n0,0\n1,1,2\n", r"line 3: 3 fields, the header has 2"),
        ("a.csv", "x,y\n0,0\n1,\n", r"line 3, column 'y' \(field 2\): empty field"),
        ("a.csv", "x,y\n0,0\n1,0\n1,0\n", r"line 3 and line 4 are at the same place"),
        ("a.csv", "x,y\n0,0\n2000,0\n", r"a.csv: .*2000 m is too long"),
        ("a.csv", "x,y\n0,0\n2e7,0\n", r"point 1 is more than 1e\+07 m from the origin"),
        ("a.csv", "x,y,theta\n0,0,0\n1,0,nan\n", r"line 3, column 'theta'"),
        ("a.yaml", "waypoints: [[0, 0], [1, 0, 2]]\n", r"waypoint 1 has a theta; all waypoints or none"),
        ("a.yaml", "waypoints: [[0, 0], [0, 0]]\n", r"waypoint 0 and waypoint 1 are at the same place"),
        ("a.yaml", "waypoints: [[0, 0], [1, .nan]]\n", r"waypoint 1: y must be a finite number"),
        ("a.yaml", "waypoints: [[0, 0], [1, 1e999]]\n", r"waypoint 1: y must be a finite number"),
        ("a.yaml", "waypoints: [[0, 0], [1, " + "9" * 400 + "]]\n", r"waypoint 1: y must be a finite number"),
        ("a.yaml", "waypoints: [[0, 0], [1, true]]\n", r"waypoint 1: y must be a finite number"),
        ("a.yaml", "waypoints: [[0, 0], [1]]\n", r"waypoint 1: expected \[x, y\]"),
        ("a.yaml", "waypoints: [[0, 0], {x: 1, z: 2}]\n", r"waypoint 1: expected keys x, y"),
        ("a.yaml", "points: [[0, 0], [1, 0]]\n", r"unknown key\(s\) 'points'"),
        ("a.yaml", "closed: yes please\nwaypoints: [[0, 0], [1, 0]]\n", r"closed must be true or false"),
        ("a.yaml", "[1, 2]\n", r"expected a mapping with 'waypoints'"),
        ("a.yaml", "a: &x [1]\nb: *x\n", r"a.yaml: invalid YAML at line 1 column 4: anchors"),
        ("a.txt", "x,y\n0,0\n1,0\n", r"a.txt: not a path file"),
    ],
)
def test_a_bad_path_file_is_refused_in_one_line_naming_where(tmp_path, name, text, message):
    f = write(tmp_path, name, text)
    with pytest.raises(PathFileError, match=message) as info:
        read_path_file(f)
    assert "\n" not in str(info.value)
    assert name in str(info.value)


def test_binary_and_folder_paths_are_refused(tmp_path):
    f = tmp_path / "b.csv"
    f.write_bytes(b"x,y\n\x00\x01\n")
    with pytest.raises(PathFileError, match=r"b.csv"):
        read_path_file(f)
    folder = tmp_path / "dir.yaml"
    folder.mkdir()
    with pytest.raises(PathFileError, match=r"dir.yaml"):
        read_path_file(folder)


def test_a_file_of_too_many_waypoints_is_refused_where_the_limit_is_passed(tmp_path, monkeypatch):
    monkeypatch.setattr(path_file, "MAX_WAYPOINTS", 10)
    rows = "".join(f"{k},0\n" for k in range(1000))
    f = write(tmp_path, "long.csv", "x,y\n" + rows)
    # header on line 1, waypoint k on line k + 2: the eleventh waypoint is line 12
    with pytest.raises(PathFileError, match=r"long.csv: line 12: more than 10 waypoints"):
        read_path_file(f)
    many = "waypoints:\n" + "".join(f"  - [{k}, 0]\n" for k in range(11))
    with pytest.raises(PathFileError, match=r"11 waypoints is too many \(at most 10\)"):
        read_path_file(write(tmp_path, "long.yaml", many))


def test_headings_in_the_file_and_a_heading_mode_are_not_both_taken(tmp_path):
    f = write(tmp_path, "t.csv", "x,y,theta\n0,0,0\n1,0,1\n")
    with pytest.raises(PathFileError, match=r"t.csv: the waypoints give theta"):
        read_path_file(f, heading="tangent")
    with pytest.raises(PathFileError, match=r"smooth path has no corners to blend"):
        read_path_file(f, smooth=True, blend=0.2)
    assert np.isclose(read_path_file(f).pose[-1, 2], 1.0)
