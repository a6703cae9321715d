"""Robot files, schema version 1 (docs/conventions.md): validation, singular layouts, round trips.

Every bad input must raise ``omnikin.errors.RobotFileError`` whose message names the
file, the wheel and the field. Expected kinematic rows are derived here by hand from
the formula of the conventions, never taken from omnikin itself.
"""

from __future__ import annotations

import copy
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
import yaml

from omnikin import PRESET_NAMES
from omnikin.errors import RobotFileError
from omnikin.io.robot_file import load_robot, parse_robot_text, robot_from_dict, robot_to_dict, save_robot
from omnikin.presets import preset_path

NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


# --- helpers -------------------------------------------------------------------------------------
def hand_row(x, y, delta, r, gamma=0.0):
    """IK row of a Swedish wheel (omni: gamma = 0), docs/conventions.md, typed in by hand."""
    a = delta + gamma
    return np.array([math.cos(a), math.sin(a), x * math.sin(a) - y * math.cos(a)]) / (r * math.cos(gamma))


def omni_wheel(name, angle_deg, distance=0.113, radius=0.04125, **extra):
    d = {"name": name, "type": "omni", "distance": distance, "angle_deg": angle_deg, "radius": radius}
    d.update(extra)
    return d


def base_robot():
    """A valid three-omni-wheel robot (the Tomasi layout) as a schema-1 mapping."""
    return {
        "omnikin": 1,
        "name": "test-omni3",
        "description": "three omni wheels",
        "wheels": [omni_wheel("w1", 0), omni_wheel("w2", 120), omni_wheel("w3", 240)],
    }


def write(tmp_path, content, name="robot.yaml"):
    path = tmp_path / name
    if isinstance(content, str):
        path.write_text(content, encoding="utf-8")
    else:
        path.write_text(yaml.safe_dump(content, sort_keys=False), encoding="utf-8")
    return path


def load_error(tmp_path, content, name="robot.yaml") -> str:
    """Load ``content`` from a file and return the RobotFileError message (must name the file)."""
    path = write(tmp_path, content, name)
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    msg = str(info.value)
    assert str(path) in msg, f"message does not name the file: {msg}"
    assert "\n" not in msg.strip(), f"message is not one line: {msg!r}"
    return msg


def with_wheel2(**changes):
    """Base robot whose wheel #2 ('w2') gets ``changes`` (value None deletes the key)."""
    data = base_robot()
    for k, v in changes.items():
        if v is None:
            data["wheels"][1].pop(k, None)
        else:
            data["wheels"][1][k] = v
    return data


W2 = ["'w2'"]  # how the message names wheel #2


def test_base_robot_is_valid(tmp_path):
    """The fixture itself loads (so every error below is caused by the mutation)."""
    robot = load_robot(write(tmp_path, base_robot()))
    assert robot.rolling_names == ["w1", "w2", "w3"]
    assert robot.mobility.campion_type == (3, 0)


# --- schema violations ----------------------------------------------------------------------------
def _mut(fn):
    def make():
        data = base_robot()
        fn(data)
        return data

    return make


def _set_top(key, value):
    return _mut(lambda d: d.__setitem__(key, value))


def _del_top(key):
    return _mut(lambda d: d.pop(key))


def _w2(**changes):
    return lambda: with_wheel2(**changes)


STEER_W2 = {"type": "steerable", "drive_deg": 0}

BAD_CASES = [
    # id, builder, fragments the message must contain (besides the file)
    ("unknown-top-key", _set_top("colour", "red"), ["colour", "unknown"]),
    ("unknown-wheel-key", _w2(colour="red"), W2 + ["colour", "unknown"]),
    ("unknown-encoder-key", _w2(encoder={"ticks_per_rev": 600, "pulses": 3}), W2 + ["encoder", "pulses"]),
    ("unknown-steer-key", _w2(**STEER_W2, steer={"offset": 0.0, "trail": 0.1}), W2 + ["steer", "trail"]),
    ("missing-omnikin", _del_top("omnikin"), ["omnikin", "missing"]),
    ("missing-name", _del_top("name"), ["'name'", "missing"]),
    ("missing-wheels", _del_top("wheels"), ["wheels", "missing"]),
    ("empty-name", _set_top("name", ""), ["'name'"]),
    ("null-name", _set_top("name", None), ["'name'"]),
    ("wheels-empty-list", _set_top("wheels", []), ["wheels"]),
    ("wheels-mapping", _set_top("wheels", {"w1": {}}), ["wheels"]),
    ("references-not-list", _set_top("references", "a paper"), ["references"]),
    ("schema-2", _set_top("omnikin", 2), ["omnikin", "2"]),
    ("schema-0", _set_top("omnikin", 0), ["omnikin"]),
    ("schema-string", _set_top("omnikin", "1"), ["omnikin"]),
    ("schema-bool", _set_top("omnikin", True), ["omnikin"]),
    ("wheel-not-mapping", _mut(lambda d: d["wheels"].__setitem__(1, "w2")), ["#2"]),
    ("missing-wheel-name", _w2(name=None), ["#2", "'name'"]),
    ("wheel-name-number", _w2(name=7), ["#2", "'name'"]),
    ("missing-wheel-type", _w2(type=None), W2 + ["'type'"]),
    ("unknown-wheel-type", _w2(type="hover"), W2 + ["'type'", "hover"]),
    ("missing-radius", _w2(radius=None), W2 + ["'radius'"]),
    ("zero-radius", _w2(radius=0), W2 + ["'radius'", "[0.0001, 10] m, got 0"]),
    ("negative-radius", _w2(radius=-0.04), W2 + ["'radius'", "-0.04"]),
    ("negative-distance", _w2(distance=-0.1), W2 + ["'distance'"]),
    ("radius-string", _w2(radius="0.04"), W2 + ["'radius'", "number"]),
    ("distance-string", _w2(distance="far"), W2 + ["'distance'", "number"]),
    ("angle-string", _w2(angle_deg="120"), W2 + ["'angle_deg'", "number"]),
    ("drive-string", _w2(drive_deg="north"), W2 + ["'drive_deg'", "number"]),
    ("ticks-string", _w2(encoder={"ticks_per_rev": "600"}), W2 + ["ticks_per_rev"]),
    ("max-speed-string", _w2(max_speed="fast"), W2 + ["max_speed"]),
    ("radius-bool", _w2(radius=True), W2 + ["'radius'", "number"]),
    ("distance-bool", _w2(distance=True), W2 + ["'distance'"]),
    ("angle-bool", _w2(angle_deg=False), W2 + ["'angle_deg'"]),
    ("drive-bool", _w2(drive_deg=True), W2 + ["'drive_deg'"]),
    ("gear-bool", _w2(encoder={"ticks_per_rev": 600, "gear_ratio": True}), W2 + ["gear_ratio"]),
    ("ticks-bool", _w2(encoder={"ticks_per_rev": True}), W2 + ["ticks_per_rev"]),
    ("max-speed-bool", _w2(max_speed=True), W2 + ["max_speed"]),
    ("offset-bool", _w2(**STEER_W2, steer={"offset": True}), W2 + ["offset"]),
    ("invert-not-bool", _w2(encoder={"ticks_per_rev": 600, "invert": "sometimes"}), W2 + ["invert"]),
    ("encoder-no-ticks", _w2(encoder={"gear_ratio": 2.0}), W2 + ["encoder", "ticks_per_rev"]),
    ("encoder-zero-ticks", _w2(encoder={"ticks_per_rev": 0}), W2 + ["ticks_per_rev"]),
    ("encoder-not-mapping", _w2(encoder=600), W2 + ["encoder"]),
    ("duplicate-wheel-name", _w2(name="w1"), ["'w1'", "#2", "'name'", "duplicate"]),
    ("polar-and-cartesian", _w2(x=0.1, y=0.0), W2 + ["distance", "x"]),
    ("only-distance", _w2(angle_deg=None), W2 + ["angle_deg"]),
    ("only-angle", _w2(distance=None), W2 + ["distance"]),
    ("only-x", _w2(distance=None, angle_deg=None, x=0.1), W2 + ["'y'"]),
    ("only-y", _w2(distance=None, angle_deg=None, y=0.1), W2 + ["'x'"]),
    ("no-placement", _w2(distance=None, angle_deg=None), W2 + ["placement"]),
    ("origin-cartesian-no-drive", _w2(distance=None, angle_deg=None, x=0.0, y=0.0), W2 + ["drive_deg", "origin"]),
    ("origin-polar-no-drive", _w2(distance=0.0), W2 + ["drive_deg", "origin"]),
    ("mecanum-roller-30", _w2(type="mecanum", roller_deg=30), W2 + ["roller_deg", "30"]),
    ("mecanum-roller-0", _w2(type="mecanum", roller_deg=0), W2 + ["roller_deg"]),
    ("mecanum-roller-missing", _w2(type="mecanum"), W2 + ["roller_deg"]),
    ("swedish-roller-missing", _w2(type="swedish", drive_deg=0), W2 + ["roller_deg"]),
    ("swedish-roller-90", _w2(type="swedish", drive_deg=0, roller_deg=90), W2 + ["roller_deg", "90"]),
    ("swedish-roller-minus-90", _w2(type="swedish", drive_deg=0, roller_deg=-90), W2 + ["roller_deg", "-90"]),
    ("swedish-roller-120", _w2(type="swedish", drive_deg=0, roller_deg=120), W2 + ["roller_deg"]),
    ("omni-roller-45", _w2(roller_deg=45), W2 + ["roller_deg", "45"]),
    ("standard-roller", _w2(type="standard", drive_deg=90, roller_deg=0), W2 + ["roller_deg"]),
    ("steerable-roller", _w2(**STEER_W2, roller_deg=10), W2 + ["roller_deg"]),
    ("steer-on-omni", _w2(steer={"min_deg": -30, "max_deg": 30}), W2 + ["steer"]),
    ("steer-on-standard", _w2(type="standard", drive_deg=90, steer={"offset": 0.0}), W2 + ["steer"]),
    ("castor-without-steer", _w2(type="castor", drive_deg=0), W2 + ["steer", "offset"]),
    ("castor-zero-offset", _w2(type="castor", drive_deg=0, steer={"offset": 0.0}), W2 + ["steer", "offset"]),
    (
        "castor-with-encoder",
        _w2(type="castor", drive_deg=0, steer={"offset": 0.02}, encoder={"ticks_per_rev": 100}),
        W2 + ["encoder"],
    ),
    ("steer-min-above-max", _w2(**STEER_W2, steer={"min_deg": 30, "max_deg": -30}), W2 + ["steer", "min_deg"]),
    ("steer-min-equals-max", _w2(**STEER_W2, steer={"min_deg": 10, "max_deg": 10}), W2 + ["steer"]),
    ("steer-min-below-180", _w2(**STEER_W2, steer={"min_deg": -200, "max_deg": 0}), W2 + ["steer"]),
    ("steer-max-above-180", _w2(**STEER_W2, steer={"min_deg": 0, "max_deg": 270}), W2 + ["steer"]),
    ("steer-negative-offset", _w2(**STEER_W2, steer={"offset": -0.02}), W2 + ["offset"]),
    ("steer-not-mapping", _w2(**STEER_W2, steer=0.02), W2 + ["steer"]),
]


@pytest.mark.parametrize("builder, fragments", [c[1:] for c in BAD_CASES], ids=[c[0] for c in BAD_CASES])
def test_schema_violation_names_file_wheel_field(tmp_path, builder, fragments):
    msg = load_error(tmp_path, builder())
    for frag in fragments:
        assert frag in msg, f"{frag!r} missing from {msg!r}"


@pytest.mark.parametrize("builder, fragments", [c[1:] for c in BAD_CASES[:12]], ids=[c[0] for c in BAD_CASES[:12]])
def test_schema_violation_from_dict_names_source(builder, fragments):
    """robot_from_dict reports the same problems under the given source name."""
    with pytest.raises(RobotFileError) as info:
        robot_from_dict(builder(), "mysource.yaml")
    assert str(info.value).startswith("mysource.yaml:")
    for frag in fragments:
        assert frag in str(info.value)


def test_first_wheel_unnamed_is_named_by_index(tmp_path):
    data = base_robot()
    del data["wheels"][0]["name"]
    msg = load_error(tmp_path, data)
    assert "#1" in msg and "'name'" in msg


# --- NaN / inf written the YAML way ----------------------------------------------------------------
NONFINITE = [
    ("radius", ".nan"),
    ("radius", ".inf"),
    ("distance", ".inf"),
    ("angle_deg", "-.inf"),
    ("angle_deg", ".NaN"),
    ("drive_deg", ".nan"),
    ("max_speed", ".inf"),
]


@pytest.mark.parametrize("field, literal", NONFINITE)
def test_yaml_nan_and_inf_rejected(tmp_path, field, literal):
    values = {"distance": "0.113", "angle_deg": "120", "radius": "0.04125"}
    values[field] = literal
    extra = "".join(f", {k}: {v}" for k, v in values.items())
    text = (
        "omnikin: 1\nname: nan-bot\nwheels:\n"
        "  - {name: w1, type: omni, distance: 0.113, angle_deg: 0, radius: 0.04125}\n"
        f"  - {{name: w2, type: omni{extra}}}\n"
        "  - {name: w3, type: omni, distance: 0.113, angle_deg: 240, radius: 0.04125}\n"
    )
    msg = load_error(tmp_path, text)
    assert "'w2'" in msg and f"'{field}'" in msg and "finite" in msg


@pytest.mark.parametrize("literal", [".nan", ".inf"])
def test_yaml_nan_in_encoder_and_steer(tmp_path, literal):
    text = (
        "omnikin: 1\nname: nan-bot\nwheels:\n"
        f"  - {{name: w1, type: omni, distance: 0.1, angle_deg: 0, radius: 0.05, "
        f"encoder: {{ticks_per_rev: {literal}}}}}\n"
    )
    msg = load_error(tmp_path, text)
    assert "'w1'" in msg and "ticks_per_rev" in msg
    text = (
        "omnikin: 1\nname: nan-bot\nwheels:\n"
        f"  - {{name: s1, type: steerable, x: 0.1, y: 0, drive_deg: 0, radius: 0.05, "
        f"steer: {{offset: {literal}}}}}\n"
    )
    msg = load_error(tmp_path, text)
    assert "'s1'" in msg and "offset" in msg


def test_json_nan_rejected(tmp_path):
    """JSON (as written by Python's json) may hold NaN / Infinity literals."""
    text = json.dumps(base_robot()).replace('"radius": 0.04125', '"radius": NaN', 1)
    assert "NaN" in text
    msg = load_error(tmp_path, text, "robot.json")
    assert "'w1'" in msg and "'radius'" in msg


def test_integer_too_large_for_a_float_is_rejected(tmp_path):
    """float() of a 401-digit integer overflows: that must be a RobotFileError, not OverflowError."""
    text = (
        "omnikin: 1\nname: big\nwheels:\n"
        "  - {name: w1, type: omni, distance: 0.113, angle_deg: 0, radius: 1" + "0" * 400 + "}\n"
    )
    msg = load_error(tmp_path, text)
    assert "'w1'" in msg and "'radius'" in msg


# --- file-level problems ------------------------------------------------------------------------------
def test_invalid_yaml_reports_line(tmp_path):
    text = (
        "omnikin: 1\nname: broken\nwheels:\n  - name: w1\n    type: omni\n   radius: 0.05\n"  # line 6: bad indentation
    )
    msg = load_error(tmp_path, text)
    assert "YAML" in msg and re.search(r"\bline 6\b", msg), msg


def test_invalid_yaml_unclosed_flow_reports_line(tmp_path):
    text = "omnikin: 1\nname: [broken\nwheels: []\n"
    msg = load_error(tmp_path, text)
    assert "YAML" in msg and re.search(r"\bline [23]\b", msg), msg


def test_invalid_json_reports_line(tmp_path):
    text = '{\n  "omnikin": 1,\n  "name": "r",\n  "wheels": [,]\n}\n'
    msg = load_error(tmp_path, text, "robot.json")
    assert "JSON" in msg and re.search(r"\bline 4\b", msg), msg


@pytest.mark.parametrize("text", ["", "\n\n   \n", "# only a comment\n"], ids=["empty", "blank", "comment"])
def test_empty_file(tmp_path, text):
    msg = load_error(tmp_path, text)
    assert "mapping" in msg


@pytest.mark.parametrize(
    "text, kind",
    [("- omnikin: 1\n- name: x\n", "list"), ("[1, 2, 3]\n", "list"), ("just words\n", "str"), ("42\n", "int")],
)
def test_top_level_not_a_mapping(tmp_path, text, kind):
    msg = load_error(tmp_path, text)
    assert "mapping" in msg and kind in msg


def test_directory_path(tmp_path):
    d = tmp_path / "robots.yaml"
    d.mkdir()
    with pytest.raises(RobotFileError) as info:
        load_robot(d)
    assert str(d) in str(info.value) and "directory" in str(info.value)


def test_missing_path_lists_presets(tmp_path):
    missing = tmp_path / "nope.yaml"
    with pytest.raises(RobotFileError) as info:
        load_robot(missing)
    msg = str(info.value)
    assert str(missing) in msg
    for name in PRESET_NAMES:
        assert name in msg


def test_unknown_preset_name_lists_presets():
    with pytest.raises(RobotFileError) as info:
        load_robot("tomasi-omni4")
    for name in PRESET_NAMES:
        assert name in str(info.value)


def test_parse_robot_text_names_source():
    with pytest.raises(RobotFileError) as info:
        parse_robot_text("omnikin: 1\nname: x\n", "inline.yaml")
    assert str(info.value).startswith("inline.yaml:") and "wheels" in str(info.value)


# --- singular and immobile layouts ------------------------------------------------------------------
def numbers_after(msg, word):
    m = re.search(word + r"[^(]*\((" + NUM + r"), (" + NUM + r")\)", msg)
    assert m, f"no point/direction after {word!r} in {msg!r}"
    return float(m.group(1)), float(m.group(2))


def test_radial_drive_lines_singular_rotation_about_origin(tmp_path):
    """Drive directions all radial: every drive line passes through the origin."""
    data = base_robot()
    for w in data["wheels"]:
        w["drive_deg"] = w["angle_deg"]
    msg = load_error(tmp_path, data)
    assert "singular" in msg and "rotation" in msg
    cx, cy = numbers_after(msg, "rotation")
    assert abs(cx) < 1e-9 and abs(cy) < 1e-9, msg


@pytest.mark.parametrize("offset_deg", [0, 10, 30, 45, 90])
def test_radial_drive_lines_message_says_origin_literally(tmp_path, offset_deg):
    """No rounding noise such as '(3.46945e-18, -0)' in the centre of rotation."""
    data = base_robot()
    for w in data["wheels"]:
        w["angle_deg"] += offset_deg
        w["drive_deg"] = w["angle_deg"]
    msg = load_error(tmp_path, data)
    assert "rotation about the point (0, 0)" in msg, msg


def test_drive_lines_through_common_point_are_singular(tmp_path):
    """Drive lines all through P = (0.05, 0.02): a rotation about P turns no wheel."""
    px, py = 0.05, 0.02
    data = base_robot()
    data["wheels"] = []
    for i, b in enumerate((10.0, 130.0, 250.0)):
        x, y = 0.2 * math.cos(math.radians(b)), 0.2 * math.sin(math.radians(b))
        data["wheels"].append(
            {
                "name": f"w{i + 1}",
                "type": "omni",
                "x": x,
                "y": y,
                "drive_deg": math.degrees(math.atan2(y - py, x - px)),
                "radius": 0.05,
            }
        )
    msg = load_error(tmp_path, data)
    cx, cy = numbers_after(msg, "rotation")
    assert cx == pytest.approx(px, abs=1e-5) and cy == pytest.approx(py, abs=1e-5), msg


def test_two_opposite_omni_wheels_are_singular(tmp_path):
    """Wheels at (+-l, 0) driving along +-y: translation along x turns neither."""
    data = base_robot()
    data["wheels"] = [omni_wheel("a", 0), omni_wheel("b", 180)]
    msg = load_error(tmp_path, data)
    assert "singular" in msg and "translation" in msg and "'a'" in msg and "'b'" in msg
    dx, dy = numbers_after(msg, "translation")
    assert abs(abs(dx) - 1.0) < 1e-6 and abs(dy) < 1e-6, msg


def test_two_omni_wheels_at_120_deg_are_singular(tmp_path):
    """Two tangential omni wheels: drive lines meet at one point, rotation about it is unseen."""
    data = base_robot()
    data["wheels"] = [omni_wheel("a", 0, distance=0.1), omni_wheel("b", 120, distance=0.1)]
    msg = load_error(tmp_path, data)
    assert "singular" in msg and "rank 2" in msg
    # drive lines: x = 0.1 (wheel a, drive +y) and the tangent at 120 deg; they meet at
    # (0.1, 0.1 tan 60) = (0.1, 0.173205)
    cx, cy = numbers_after(msg, "rotation")
    assert cx == pytest.approx(0.1, abs=1e-5) and cy == pytest.approx(0.1 * math.tan(math.radians(60)), abs=1e-5)


def test_single_omni_wheel_is_singular(tmp_path):
    data = base_robot()
    data["wheels"] = [omni_wheel("only", 0)]
    msg = load_error(tmp_path, data)
    assert "singular" in msg


def test_three_fixed_wheels_not_on_one_axle_are_immobile(tmp_path):
    """Three standard wheels with tangent axles (radial drive): no motion is admissible."""
    data = base_robot()
    data["wheels"] = [
        {"name": n, "type": "standard", "distance": 0.2, "angle_deg": b, "drive_deg": b, "radius": 0.05}
        for n, b in (("a", 0), ("b", 120), ("c", 240))
    ]
    msg = load_error(tmp_path, data)
    assert "immobile" in msg and "mobility 0" in msg
    for n in ("'a'", "'b'", "'c'"):
        assert n in msg


def test_three_fixed_tangent_wheels_rotate_in_place(tmp_path):
    """Control for the immobile case: tangent drive directions leave rotation about the origin."""
    data = base_robot()
    data["wheels"] = [
        {"name": n, "type": "standard", "distance": 0.2, "angle_deg": b, "drive_deg": b + 90, "radius": 0.05}
        for n, b in (("a", 0), ("b", 120), ("c", 240))
    ]
    robot = load_robot(write(tmp_path, data))
    assert robot.mobility.degree_of_mobility == 1


def test_mecanum_all_plus_45_rank_deficient(tmp_path):
    """Four mecanum wheels, all roller +45: rows (1, 1, x - y)/r; translation (1, -1) unseen."""
    data = base_robot()
    data["wheels"] = [
        {"name": n, "type": "mecanum", "x": x, "y": y, "drive_deg": 0, "roller_deg": 45, "radius": 0.0475}
        for n, x, y in (("fl", 0.2355, 0.15), ("fr", 0.2355, -0.15), ("rl", -0.2355, 0.15), ("rr", -0.2355, -0.15))
    ]
    msg = load_error(tmp_path, data)
    assert "singular" in msg and "rank 2" in msg and "translation" in msg
    dx, dy = numbers_after(msg, "translation")
    assert abs(abs(dx) - math.sqrt(0.5)) < 1e-5 and abs(dx + dy) < 1e-5, msg


def test_mecanum_x_arrangement_is_fine_and_matches_hand_rows(tmp_path):
    """Control: the X arrangement loads; rows follow the Swedish formula with gamma in degrees."""
    rolls = {"fl": -45, "fr": 45, "rl": 45, "rr": -45}
    pos = {"fl": (0.2355, 0.15), "fr": (0.2355, -0.15), "rl": (-0.2355, 0.15), "rr": (-0.2355, -0.15)}
    data = base_robot()
    data["wheels"] = [
        {
            "name": n,
            "type": "mecanum",
            "x": pos[n][0],
            "y": pos[n][1],
            "drive_deg": 0,
            "roller_deg": rolls[n],
            "radius": 0.0475,
        }
        for n in rolls
    ]
    robot = load_robot(write(tmp_path, data))
    for row, n in zip(robot.ik_matrix, rolls, strict=True):
        g = rolls[n]
        # gamma = +-45, delta = 0: (1, tan g, x tan g - y) / r
        t = math.tan(math.radians(g))
        expected = np.array([1.0, t, pos[n][0] * t - pos[n][1]]) / 0.0475
        np.testing.assert_allclose(row, expected, atol=1e-12)


# --- kinematics read from the file -----------------------------------------------------------------------
def test_default_drive_is_counter_clockwise_tangent(tmp_path):
    """Wheel at beta = 30 deg, no drive_deg: row = (-sin b, cos b, l) / r."""
    dist, r, b = 0.2, 0.05, math.radians(30.0)
    data = base_robot()
    data["wheels"] = [
        omni_wheel("w1", 30, distance=dist, radius=r),
        omni_wheel("w2", 150, distance=dist, radius=r),
        omni_wheel("w3", 270, distance=dist, radius=r),
    ]
    robot = load_robot(write(tmp_path, data))
    expected = np.array([-math.sin(b), math.cos(b), dist]) / r
    np.testing.assert_allclose(robot.ik_matrix[0], expected, atol=1e-12)
    # the explicit counter-clockwise tangent gives the same row, the clockwise one its negative
    data["wheels"][0]["drive_deg"] = 120
    np.testing.assert_allclose(load_robot(write(tmp_path, data)).ik_matrix[0], expected, atol=1e-12)
    data["wheels"][0]["drive_deg"] = -60
    np.testing.assert_allclose(load_robot(write(tmp_path, data)).ik_matrix[0], -expected, atol=1e-12)


def test_tomasi_preset_rows_by_hand():
    dist, r = 0.113, 0.04125
    robot = load_robot("tomasi-omni3")
    for row, deg in zip(robot.ik_matrix, (0, 120, 240), strict=True):
        b = math.radians(deg)
        np.testing.assert_allclose(row, np.array([-math.sin(b), math.cos(b), dist]) / r, atol=1e-12)


@pytest.mark.parametrize("deg", [30.0, 120.0, 225.0, -60.0, 0.0, 90.0, 180.0])
@pytest.mark.parametrize("drive", [None, 17.0])
def test_polar_and_cartesian_placement_identical(tmp_path, deg, drive):
    dist, b = 0.137, math.radians(deg)
    polar = {"name": "p", "type": "omni", "distance": dist, "angle_deg": deg, "radius": 0.03}
    cart = {"name": "p", "type": "omni", "x": dist * math.cos(b), "y": dist * math.sin(b), "radius": 0.03}
    if drive is not None:
        polar["drive_deg"] = cart["drive_deg"] = drive
    rows = []
    for w in (polar, cart):
        data = base_robot()
        data["wheels"] = [w, omni_wheel("q", deg + 120), omni_wheel("s", deg + 240)]
        rows.append(load_robot(write(tmp_path, data)).ik_matrix[0])
    np.testing.assert_allclose(rows[0], rows[1], atol=1e-12)
    delta = b + math.pi / 2 if drive is None else math.radians(drive)
    np.testing.assert_allclose(rows[0], hand_row(dist * math.cos(b), dist * math.sin(b), delta, 0.03), atol=1e-12)


def test_swedish_roller_angle_row(tmp_path):
    """A swedish wheel of roller 30 deg follows the conventions' row exactly."""
    data = base_robot()
    data["wheels"][0] = {
        "name": "w1",
        "type": "swedish",
        "x": 0.1,
        "y": 0.05,
        "drive_deg": 80,
        "roller_deg": 30,
        "radius": 0.04,
    }
    robot = load_robot(write(tmp_path, data))
    np.testing.assert_allclose(
        robot.ik_matrix[0], hand_row(0.1, 0.05, math.radians(80), 0.04, math.radians(30)), atol=1e-12
    )


def test_encoder_and_limits_read(tmp_path):
    data = base_robot()
    data["wheels"][0]["encoder"] = {"ticks_per_rev": 500, "gear_ratio": 19.7, "invert": True}
    data["wheels"][0]["max_speed"] = 12.5
    robot = load_robot(write(tmp_path, data))
    enc = robot.wheels[0].encoder
    assert enc.rad_per_tick == pytest.approx(-2 * math.pi / (500 * 19.7))
    assert robot.wheels[0].max_speed == 12.5


def test_steer_limits_in_degrees(tmp_path):
    data = base_robot()
    data["wheels"][1] = {
        "name": "w2",
        "type": "steerable",
        "distance": 0.113,
        "angle_deg": 120,
        "drive_deg": 0,
        "radius": 0.04,
        "steer": {"offset": 0.01, "min_deg": -45, "max_deg": 90},
    }
    robot = load_robot(write(tmp_path, data))
    s = robot.wheels[1].steer
    assert (s.offset, s.lower, s.upper) == pytest.approx((0.01, -math.pi / 4, math.pi / 2))


def test_json_file_accepted(tmp_path):
    path = tmp_path / "robot.json"
    path.write_text(json.dumps(base_robot(), indent=2), encoding="utf-8")
    robot = load_robot(path)
    np.testing.assert_allclose(robot.ik_matrix, load_robot("tomasi-omni3").ik_matrix, atol=1e-12)


@pytest.mark.parametrize("suffix", [".yaml", ".json"])
def test_byte_order_mark_accepted(tmp_path, suffix):
    """Editors on Windows may save a UTF-8 byte-order mark first."""
    data = base_robot()
    text = json.dumps(data) if suffix == ".json" else yaml.safe_dump(data)
    path = tmp_path / f"bom{suffix}"
    path.write_bytes(b"\xef\xbb\xbf" + text.encode("utf-8"))
    np.testing.assert_allclose(load_robot(path).ik_matrix, load_robot("tomasi-omni3").ik_matrix, atol=1e-12)


# --- round trips ---------------------------------------------------------------------------------------
def assert_same_robot(a, b):
    assert a.name == b.name and a.description == b.description and a.references == b.references
    assert [w.name for w in a.wheels] == [w.name for w in b.wheels]
    assert [w.type for w in a.wheels] == [w.type for w in b.wheels]
    np.testing.assert_allclose(a.ik_matrix, b.ik_matrix, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(a.fixed_constraints, b.fixed_constraints, atol=1e-10)
    if a.steerable:
        steer = np.linspace(-0.4, 0.5, len(a.steerable))
        np.testing.assert_allclose(a.jacobian(steer), b.jacobian(steer), atol=1e-10)
    for wa, wb in zip(a.wheels, b.wheels, strict=True):
        assert wa.encoder == wb.encoder and wa.max_speed == wb.max_speed
        if wa.steer is None:
            assert wb.steer is None
        else:
            assert (wa.steer.offset, wa.steer.lower, wa.steer.upper) == pytest.approx(
                (wb.steer.offset, wb.steer.lower, wb.steer.upper), abs=1e-12
            )
        assert wa.roller == pytest.approx(wb.roller, abs=1e-12)
    assert a.mobility.campion_type == b.mobility.campion_type


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_round_trip_dict(name):
    robot = load_robot(name)
    data = robot_to_dict(robot)
    assert data["omnikin"] == 1
    assert_same_robot(robot, robot_from_dict(copy.deepcopy(data), "dict"))


@pytest.mark.parametrize("suffix", [".yaml", ".yml", ".json"])
@pytest.mark.parametrize("name", PRESET_NAMES)
def test_round_trip_file(tmp_path, name, suffix):
    robot = load_robot(name)
    path = tmp_path / f"{name}{suffix}"
    save_robot(robot, path)
    text = path.read_text(encoding="utf-8")
    if suffix == ".json":
        assert json.loads(text)["omnikin"] == 1
    else:
        assert yaml.safe_load(text)["omnikin"] == 1
    again = load_robot(path)
    assert_same_robot(robot, again)
    # and a second generation is stable
    path2 = tmp_path / f"again{suffix}"
    save_robot(again, path2)
    assert_same_robot(robot, load_robot(path2))


def test_round_trip_preserves_hand_edited_robot(tmp_path):
    """A robot using every optional field survives save/load."""
    data = {
        "omnikin": 1,
        "name": "kitchen-sink",
        "description": "all the fields",
        "references": ["a", "b"],
        "wheels": [
            {
                "name": "m",
                "type": "mecanum",
                "x": 0.2,
                "y": 0.1,
                "drive_deg": 10,
                "roller_deg": -45,
                "radius": 0.05,
                "encoder": {"ticks_per_rev": 2048, "gear_ratio": 3.5, "invert": True},
                "max_speed": 20.0,
            },
            {
                "name": "s",
                "type": "swedish",
                "distance": 0.2,
                "angle_deg": 135,
                "drive_deg": 225,
                "roller_deg": 20,
                "radius": 0.04,
            },
            {"name": "o", "type": "omni", "distance": 0.25, "angle_deg": 250, "roller_deg": 0, "radius": 0.04},
            {
                "name": "c",
                "type": "castor",
                "x": -0.3,
                "y": 0.0,
                "drive_deg": 0,
                "radius": 0.02,
                "steer": {"offset": 0.03},
            },
        ],
    }
    robot = load_robot(write(tmp_path, data))
    for suffix in (".yaml", ".json"):
        path = tmp_path / f"out{suffix}"
        save_robot(robot, path)
        assert_same_robot(robot, load_robot(path))


# --- ranges of every numeric field (docs/conventions.md, "Ranges") ---------------------------------------
STEER_W2_AT = {"type": "steerable", "drive_deg": 0}
RANGE_CASES = [
    # id, wheel-2 changes, field named in the message, documented (low, high), values accepted at the ends
    ("x", lambda v: {"distance": None, "angle_deg": None, "x": v, "y": 0.1}, "'x'", (-1000, 1000), None),
    ("y", lambda v: {"distance": None, "angle_deg": None, "x": 0.1, "y": v}, "'y'", (-1000, 1000), None),
    ("distance", lambda v: {"distance": v, "drive_deg": 90}, "'distance'", (0, 1000), None),
    ("angle_deg", lambda v: {"angle_deg": v, "drive_deg": 0}, "'angle_deg'", (-720, 720), None),
    ("drive_deg", lambda v: {"drive_deg": v}, "'drive_deg'", (-720, 720), None),
    ("roller_deg", lambda v: {"type": "swedish", "drive_deg": 90, "roller_deg": v}, "'roller_deg'", (-80, 80), None),
    ("radius", lambda v: {"radius": v}, "'radius'", (1e-4, 10), None),
    ("max_speed", lambda v: {"max_speed": v}, "'max_speed'", (1e-3, 1e4), None),
    ("ticks_per_rev", lambda v: {"encoder": {"ticks_per_rev": v}}, "encoder.ticks_per_rev", (1, 2.0**32), None),
    (
        "gear_ratio",
        lambda v: {"encoder": {"ticks_per_rev": 100, "gear_ratio": v}},
        "encoder.gear_ratio",
        (1e-3, 1e4),
        None,
    ),
    ("steer.offset", lambda v: {**STEER_W2_AT, "steer": {"offset": v}}, "steer.offset", (0, 10), None),
    (
        "steer.min_deg",
        lambda v: {**STEER_W2_AT, "steer": {"min_deg": v, "max_deg": 180}},
        "steer.min_deg",
        (-180, 180),
        (-180, 179),
    ),
    (
        "steer.max_deg",
        lambda v: {**STEER_W2_AT, "steer": {"min_deg": -180, "max_deg": v}},
        "steer.max_deg",
        (-180, 180),
        (-179, 180),
    ),
]


@pytest.mark.parametrize(
    "changes, field, bounds, inside", [c[1:] for c in RANGE_CASES], ids=[c[0] for c in RANGE_CASES]
)
def test_every_numeric_field_is_range_checked(tmp_path, changes, field, bounds, inside):
    low, high = bounds
    for value in inside or bounds:
        load_robot(write(tmp_path, with_wheel2(**changes(value))))  # the ends of the range are fine
    for outside in (low - max(abs(low), 1) * 1e-3, high + max(abs(high), 1) * 1e-3, 1e300, -1e300):
        msg = load_error(tmp_path, with_wheel2(**changes(outside)))
        assert "'w2'" in msg and field in msg and "must lie in [" in msg, msg


@pytest.mark.parametrize("tpr, gear", [(1e-310, 1.0), (1e-200, 1.0), (100, 1e-310), (100, 1e-200), (100, 1e300)])
def test_encoder_values_that_once_gave_nan_poses_are_refused(tmp_path, tpr, gear):
    """ticks_per_rev 1e-310 made rad_per_tick inf (NaN poses), 1e-200 * gear overflowed a division."""
    msg = load_error(tmp_path, with_wheel2(encoder={"ticks_per_rev": tpr, "gear_ratio": gear}))
    assert "'w2'" in msg and ("ticks_per_rev" in msg or "gear_ratio" in msg) and "must lie in" in msg


# --- names (docs/conventions.md, "Names") ----------------------------------------------------------------------
@pytest.mark.parametrize(
    "name",
    ["", " w2", "w2 ", "w 2", "w,2", 'w"2', "w'2", "w\n2", "w\t2", "2w", "_w", "w-2", "w.2", "wä", "x" * 65, "t"],
    ids=[
        "empty",
        "leading-blank",
        "trailing-blank",
        "blank",
        "comma",
        "double-quote",
        "quote",
        "newline",
        "tab",
        "digit-first",
        "underscore-first",
        "hyphen",
        "dot",
        "non-ascii",
        "65-chars",
        "time-column",
    ],
)
def test_wheel_names_unusable_as_csv_column_or_ros_name_are_refused(tmp_path, name):
    msg = load_error(tmp_path, with_wheel2(name=name))
    assert "#2" in msg and "'name'" in msg, msg


def test_longest_and_plain_wheel_names_are_accepted(tmp_path):
    data = base_robot()
    names = ["a" * 64, "Front_Left_2", "T"]
    for w, n in zip(data["wheels"], names, strict=True):
        w["name"] = n
    assert load_robot(write(tmp_path, data)).wheel_names == names


@pytest.mark.parametrize(
    "other, steer_type",
    [("a_steer_deg", "steerable"), ("a_steer", "steerable"), ("a_steer_deg", "omni"), ("a_steer", "omni")],
)
def test_wheel_named_like_a_derived_column_or_joint_is_refused(tmp_path, other, steer_type):
    """Tick logs have a column <wheel>_steer_deg and joint_states a joint <wheel>_steer: a wheel of that
    name would read another wheel's steering angle as its ticks (refused for any wheel types)."""
    data = base_robot()
    data["wheels"][0]["name"] = "a"
    if steer_type == "steerable":
        data["wheels"][0].update(type="steerable", drive_deg=90)
    data["wheels"][2]["name"] = other
    msg = load_error(tmp_path, data)
    assert f"wheel {other!r} (#3)" in msg and "'name'" in msg and "wheel 'a' (#1)" in msg, msg


def test_duplicate_wheel_name_names_both_wheels(tmp_path):
    msg = load_error(tmp_path, with_wheel2(name="w1"))
    assert "wheel 'w1' (#2)" in msg and "also wheel #1" in msg


@pytest.mark.parametrize(
    "name",
    ["two\nlines", "x" * 129, " padded", "bell\a"],
    ids=["newline", "129-chars", "leading-blank", "control-char"],
)
def test_robot_names_that_break_one_line_messages_are_refused(tmp_path, name):
    data = base_robot()
    data["name"] = name
    msg = load_error(tmp_path, data)
    assert "field 'name'" in msg


def test_core_refuses_the_same_names():
    """Robot built in Python: the same rules hold (a tick log written for it could not be read)."""
    from omnikin import InputError, Robot, Wheel

    def wheel(name, angle):
        b = math.radians(angle)
        return Wheel(name, "omni", 0.1 * math.cos(b), 0.1 * math.sin(b), b + math.pi / 2, 0.05)

    with pytest.raises(InputError, match="not a valid wheel name"):
        wheel("w 1", 0)
    with pytest.raises(InputError, match="reserved"):
        wheel("t", 0)
    with pytest.raises(InputError, match="'a_steer_deg' is taken by the steering column"):
        Robot("r", (wheel("a", 0), wheel("b", 120), wheel("a_steer_deg", 240)))
    with pytest.raises(InputError, match="duplicate wheel name 'a'"):
        Robot("r", (wheel("a", 0), wheel("b", 120), wheel("a", 240)))
    with pytest.raises(InputError, match="robot name"):
        Robot("two\nlines", (wheel("a", 0), wheel("b", 120), wheel("c", 240)))


# --- default drive direction (docs/conventions.md, "Default drive direction") ----------------------------------
def mecanum_robot(lx, ly, r, drive_deg=None):
    """Four mecanum wheels in the X arrangement, as the mecanum4 preset (rollers -45 front-left/rear-right)."""
    wheels = []
    for name, x, y, roller in (("fl", lx, ly, -45), ("fr", lx, -ly, 45), ("rl", -lx, ly, 45), ("rr", -lx, -ly, -45)):
        w = {"name": name, "type": "mecanum", "x": x, "y": y, "roller_deg": roller, "radius": r}
        if drive_deg is not None:
            w["drive_deg"] = drive_deg
        wheels.append(w)
    return {"omnikin": 1, "name": "mecanum", "wheels": wheels}


@pytest.mark.parametrize("lx, ly, r", [(0.2355, 0.15, 0.0475), (0.5, 0.05, 0.1), (0.3, 0.3, 0.076)])
def test_mecanum_without_drive_deg_follows_the_standard_mecanum_equations(tmp_path, lx, ly, r):
    """Muir & Neuman (1987), Taheri, Qiao & Ghaeminezhad (2015), wheels fl, fr, rl, rr:
    omega = [vx - vy - (lx+ly) w, vx + vy + (lx+ly) w, vx + vy - (lx+ly) w, vx - vy + (lx+ly) w] / r."""
    robot = load_robot(write(tmp_path, mecanum_robot(lx, ly, r)))
    k = lx + ly
    for vx, vy, w in ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0), (0.3, -0.2, 0.7)):
        expected = np.array([vx - vy - k * w, vx + vy + k * w, vx + vy - k * w, vx - vy + k * w]) / r
        np.testing.assert_allclose(robot.ik([vx, vy, w]).wheel_speeds, expected, atol=1e-9)
    # the closed form is isotropic with length lx + ly: J^T J = (4 / r^2) diag(1, 1, k^2)
    assert robot.mobility.condition_number == pytest.approx(1.0, abs=1e-9)
    explicit = load_robot(write(tmp_path, mecanum_robot(lx, ly, r, drive_deg=0)))
    np.testing.assert_allclose(robot.ik_matrix, explicit.ik_matrix, atol=1e-15)


def test_mecanum4_preset_matches_its_file_without_drive_deg(tmp_path):
    text = (Path(preset_path("mecanum4"))).read_text().replace("drive_deg: 0, ", "")
    assert "drive_deg" not in text.split("wheels:")[1]
    robot = load_robot(write(tmp_path, text))
    np.testing.assert_allclose(robot.ik_matrix, load_robot("mecanum4").ik_matrix, atol=1e-15)


@pytest.mark.parametrize(
    "kind, extra",
    [("swedish", {"roller_deg": 30}), ("standard", {}), ("steerable", {}), ("castor", {"steer": {"offset": 0.02}})],
)
def test_types_without_a_universal_mounting_must_give_drive_deg(tmp_path, kind, extra):
    msg = load_error(tmp_path, with_wheel2(type=kind, **extra))
    assert "'w2'" in msg and "'drive_deg'" in msg and f"required for a {kind} wheel" in msg
    assert "0: along body +x" in msg


def test_omni_default_is_still_the_counter_clockwise_tangent(tmp_path):
    robot = load_robot(write(tmp_path, base_robot()))
    b = math.radians(120)
    np.testing.assert_allclose(
        robot.ik_matrix[1], hand_row(0.113 * math.cos(b), 0.113 * math.sin(b), b + math.pi / 2, 0.04125), atol=1e-12
    )


# --- messages stay one bounded line whatever the value ----------------------------------------------------------
HUGE_TEXT = "x" * 1_000_000
HUGE_LIST = list(range(100_000))
BOUNDED_CASES = [
    ("name", _set_top("name", HUGE_TEXT)),
    ("name-list", _set_top("name", HUGE_LIST)),
    ("description", _set_top("description", HUGE_LIST)),
    ("references", _set_top("references", [HUGE_TEXT, 1])),
    ("wheels", _set_top("wheels", {"k": HUGE_LIST})),
    ("schema", _set_top("omnikin", HUGE_TEXT)),
    ("unknown-top-keys", _mut(lambda d: d.update({f"k{i}": i for i in range(20_000)}))),
    ("unknown-wheel-keys", _w2(**{f"k{i}": i for i in range(20_000)})),
    ("wheel-name", _w2(name=HUGE_TEXT)),
    ("wheel-type", _w2(type=HUGE_TEXT)),
    ("wheel-not-mapping", _mut(lambda d: d["wheels"].__setitem__(1, HUGE_LIST))),
    ("radius", _w2(radius=HUGE_TEXT)),
    ("radius-list", _w2(radius=HUGE_LIST)),
    ("encoder", _w2(encoder=HUGE_LIST)),
    ("invert", _w2(encoder={"ticks_per_rev": 100, "invert": HUGE_TEXT})),
    ("steer", _w2(**STEER_W2, steer=HUGE_TEXT)),
    ("roller", _w2(type="mecanum", roller_deg=HUGE_TEXT)),
    ("omni-roller", _w2(roller_deg=HUGE_TEXT)),
    ("radius-int-beyond-repr", _w2(radius=10**5000)),  # repr() of it raises ValueError
    ("name-int-beyond-repr", _w2(name=10**5000)),
    ("schema-int-beyond-repr", _set_top("omnikin", 10**5000)),
    ("counter-bits-beyond-repr", _w2(encoder={"ticks_per_rev": 100, "counter_bits": 10**5000})),
]


@pytest.mark.parametrize("builder", [c[1] for c in BOUNDED_CASES], ids=[c[0] for c in BOUNDED_CASES])
def test_messages_quote_huge_values_shortened(builder):
    with pytest.raises(RobotFileError) as info:
        robot_from_dict(builder(), "big.yaml")
    msg = str(info.value)
    assert msg.startswith("big.yaml: ") and "\n" not in msg and len(msg) < 600, msg[:1000]
