"""World files: the schema's form loads, every problem is one line naming file, line, body and field."""

from __future__ import annotations

import math
import time
import tracemalloc

import pytest
import yaml

from omnikin.errors import WorldFileError
from omnikin.io.world_file import load_world, parse_world_text, world_from_dict, world_to_dict
from omnikin.world import Box, Cylinder, Floor, Patch, Wall, make_world
from omnikin.world.model import MAX_WALL_SEGMENTS

ISSUE_FORM = """\
omnikin_world: 1
name: box-room
start: [0, 0, 0]
walls:
  - {points: [[-2, -2], [2, -2], [2, 2], [-2, 2], [-2, -2]], thickness: 0.05, height: 0.3}
obstacles:
  - {shape: box, center: [1, 0.5], size: [0.3, 0.3, 0.3], yaw_deg: 0, fixed: true}
  - {shape: cylinder, center: [-1, 1], radius: 0.2, height: 0.3, fixed: false, mass: 2.0}
floor:
  friction: 1.0
  patches: [{polygon: [[0.5, -1], [1.5, -1], [1.5, 1], [0.5, 1]], friction: 0.05}]
"""


def _error(text: str, tmp_path) -> str:
    path = tmp_path / "world.yaml"
    path.write_text(text)
    with pytest.raises(WorldFileError) as caught:
        load_world(path)
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith(str(path))
    return message


def test_the_documented_form_loads_with_its_values_in_si_units(tmp_path):
    path = tmp_path / "room.yaml"
    path.write_text(ISSUE_FORM.replace("start: [0, 0, 0]", "start: [0.5, -0.25, 90]"))
    world = load_world(path)
    assert world.name == "box-room"
    assert world.start == pytest.approx((0.5, -0.25, math.pi / 2))
    assert world.walls[0].points[1] == (2.0, -2.0)
    assert (world.walls[0].thickness, world.walls[0].height) == (0.05, 0.3)
    box, cylinder = world.obstacles
    assert isinstance(box, Box) and box.size == (0.3, 0.3, 0.3) and box.fixed and box.mass is None
    assert isinstance(cylinder, Cylinder) and cylinder.radius == 0.2 and not cylinder.fixed and cylinder.mass == 2.0
    assert world.floor.patches[0].friction == 0.05
    assert world.bodies == ("wall 1", "box 1", "cylinder 2")


def test_a_world_written_out_reads_back_the_same(tmp_path):
    world = parse_world_text(ISSUE_FORM.replace("yaw_deg: 0", "yaw_deg: 30"), "w.yaml")
    text = yaml.safe_dump(world_to_dict(world), sort_keys=False)
    again = parse_world_text(text, "again.yaml")
    assert again == world


@pytest.mark.parametrize(
    ("old", "new", "line", "expected"),
    [
        ("thickness: 0.05", "thickness: 0", 5, "wall #1: field 'thickness': must lie in [0.001, 10] m, got 0"),
        ("fixed: false, mass: 2.0", "fixed: false", 8, "obstacle #2: field 'mass': a movable obstacle"),
        ("fixed: true}", "fixed: true, mass: 3}", 7, "obstacle #1: field 'mass': a fixed obstacle has no mass"),
        ("center: [-1, 1]", "center: [1, 0.5]", 8, "obstacle #2: field 'center': a movable obstacle overlaps 'box 1'"),
        ("yaw_deg: 0", "yaw_de: 0", 7, "did you mean 'yaw_deg'?"),
        ("yaw_deg: 0", "yaw_deg: .nan", 7, "obstacle #1: field 'yaw_deg': must be finite"),
        (
            "shape: box",
            "shape: boxx",
            7,
            "obstacle #1: unknown shape 'boxx'; one of ['box', 'cylinder']; did you mean 'box'?",
        ),
        ("radius: 0.2", "radius: -0.2", 8, "obstacle #2: field 'radius': must lie in"),
        ("friction: 0.05", "friction: 0", 11, "patch #1: field 'friction': must lie in"),
        ("[1.5, 1], [0.5, 1]", "[0.5, 1], [1.5, 1]", 11, "patch #1: field 'polygon': edges"),
        (
            "[2, -2], [2, 2]",
            "[2, -2], [2, -2]",
            5,
            "wall #1: field 'points': points 1 and 2 (from 0) are closer than 1 mm",
        ),
        ("start: [0, 0, 0]", "start: [0, 0]", 3, "field 'start': must be [x, y, yaw_deg]"),
        ("start: [0, 0, 0]", "start: [0, 1e9, 0]", 3, "field 'start': must lie in [-1000, 1000] m"),
        ("omnikin_world: 1", "omnikin_world: 2", 1, "unsupported world schema version 2"),
        ("name: box-room", "name: ' box'", 2, "field 'name': printable characters without blanks"),
    ],
)
def test_a_bad_field_is_named_with_its_file_line_and_body(tmp_path, old, new, line, expected):
    assert old in ISSUE_FORM
    message = _error(ISSUE_FORM.replace(old, new), tmp_path)
    assert f": line {line}: " in message
    assert expected in message


def test_overlapping_patches_are_refused_but_patches_sharing_an_edge_are_not(tmp_path):
    second = "{polygon: [[1.5, -1], [2.5, -1], [2.5, 1], [1.5, 1]], friction: 0.5}"
    touching = ISSUE_FORM.replace("friction: 0.05}]", f"friction: 0.05}}, {second}]")
    path = tmp_path / "ok.yaml"
    path.write_text(touching)
    assert len(load_world(path).floor.patches) == 2
    inside = "{polygon: [[0.8, -0.5], [1.2, -0.5], [1.2, 0.5]], friction: 0.5}"
    message = _error(ISSUE_FORM.replace("friction: 0.05}]", f"friction: 0.05}}, {inside}]"), tmp_path)
    assert "patch #2: field 'polygon': overlaps patch #1" in message


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("omnikin_world: 1\nname: a\nwalls: &w []\nmarks: *w\n", "anchors (&name) and aliases"),
        ("omnikin_world: 1\nname: a\nname: b\n", "duplicate key 'name'"),
        ("omnikin_world: 1\nname: a\nwalls: [{points: [[0, 0], [0x10, 0]]}]\n", "hexadecimal"),
        ("omnikin_world: 1\nname: a\nwalls: {points: []}\n", "field 'walls': must be a list of walls"),
        ("omnikin_world: 1\nname: a\nflor: {}\n", "did you mean 'floor'?"),
        ("omnikin_world: 1\n", "field 'name': missing required key"),
        ("- 1\n", "a world file must be a mapping at top level"),
        ("omnikin_world: 1\nname: a\nwalls: [{points: [[0, 0], [1, 0]], thickness: !!float 1}]\n", "explicit tag"),
    ],
)
def test_hostile_yaml_is_refused_in_one_line(tmp_path, text, expected):
    assert expected in _error(text, tmp_path)


def test_a_flood_of_walls_is_refused_quickly_and_in_little_memory(tmp_path):
    points = ", ".join(f"[{i % 2}, {i * 0.01:.2f}]" for i in range(MAX_WALL_SEGMENTS + 2))
    path = tmp_path / "flood.yaml"
    path.write_text(f"omnikin_world: 1\nname: flood\nwalls: [{{points: [{points}]}}]\n")
    tracemalloc.start()
    began = time.process_time()
    with pytest.raises(WorldFileError, match=r"wall #1: field 'points': must be a list of 2 to 2001 points"):
        load_world(path)
    seconds = time.process_time() - began
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert seconds < 5.0
    assert peak < 50e6
    many = "\n".join(f"  - {{points: [[{i}, 0], [{i}, 1]]}}" for i in range(MAX_WALL_SEGMENTS + 1))
    path.write_text(f"omnikin_world: 1\nname: flood\nwalls:\n{many}\n")
    with pytest.raises(WorldFileError, match=r"field 'walls': 2001 entries, at most 2000"):
        load_world(path)


def test_a_file_too_large_or_not_a_file_is_refused(tmp_path):
    big = tmp_path / "big.yaml"
    big.write_text("# " + "x" * 300_000 + "\n")
    with pytest.raises(WorldFileError, match="big.yaml"):
        load_world(big)
    with pytest.raises(WorldFileError, match="folder|directory|regular"):
        load_world(tmp_path)


def test_worlds_built_in_python_are_checked_as_files_are():
    with pytest.raises(WorldFileError, match=r"wall #1: field 'thickness': must be finite, got nan"):
        make_world("w", walls=[Wall(((0, 0), (1, 0)), thickness=float("nan"))])
    with pytest.raises(WorldFileError, match=r"obstacle #1: field 'fixed': must be true or false"):
        make_world("w", obstacles=[Box((0, 0), (1, 1, 1), fixed="yes")])
    with pytest.raises(WorldFileError, match=r"'wall 1' is also the name of wall #1"):
        make_world("w", walls=[Wall(((0, 0), (1, 0))), Wall(((0, 2), (1, 2)), name="wall 1")])
    world = make_world("w", floor=Floor(size=(4, 6), patches=(Patch(((0, 0), (1, 0), (1, 1), (0, 0)), 0.1),)))
    assert world.floor.patches[0].polygon == ((0.0, 0.0), (1.0, 0.0), (1.0, 1.0))  # closed as written
    assert world.floor_bounds == (-2.0, -3.0, 2.0, 3.0)


def test_a_dict_without_lines_still_names_body_and_field():
    with pytest.raises(WorldFileError) as caught:
        world_from_dict({"omnikin_world": 1, "name": "w", "walls": [{"points": [[0, 0]]}]}, "w.yaml")
    assert str(caught.value).startswith("w.yaml: wall #1: field 'points': must be a list of 2 to")


def test_bodies_of_the_wrong_kind_or_no_list_are_one_line_errors():
    with pytest.raises(WorldFileError, match=r"field 'walls': must be a list, got None"):
        make_world("w", walls=None)
    with pytest.raises(WorldFileError, match=r"mark #1: must be a Mark, got Wall"):
        make_world("w", marks=[Wall(((0, 0), (1, 0)))])
    with pytest.raises(WorldFileError, match=r"field 'start': must be a pose"):
        make_world("w", start=None)
