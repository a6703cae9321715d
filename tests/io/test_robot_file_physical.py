"""Robot files with physical fields (docs/conventions.md, "Physical fields").

The fields are optional additions to schema 1: every one is read back as written, written back
by the robot-file writer, and refused like every other field of the file when wrong, in one line
naming the file, the wheel and the field (YAML number forms: the line and column). The expected
messages are typed in from the conventions (ranges, wording of the loader's other fields), and
lines and columns are counted in the text the test writes, not taken from the loader.
"""

from __future__ import annotations

import json

import pytest

from omnikin import PRESET_NAMES
from omnikin.errors import RobotFileError
from omnikin.io.robot_file import load_robot, robot_to_dict, save_robot
from omnikin.kinematics.physical import PhysicalBody, PhysicalWheel

WHEEL_KEYS = "['friction', 'mass', 'max_torque', 'rollers', 'rows', 'width']"
BODY_KEYS = "['com', 'height', 'mass']"


def robot_yaml(top: str | None = None, w2: str | None = None, w2_kind: str = "type: omni") -> str:
    """A three-omni-wheel robot; ``top`` is the text after ``physical:`` at the top level (line 3),
    ``w2`` the text after ``physical:`` in wheel 'w2' (its own line), ``w2_kind`` its type keys."""
    lines = ["omnikin: 1", "name: phys"]
    if top is not None:
        lines.append(f"physical: {top}")
    lines += [
        "wheels:",
        "  - {name: w1, type: omni, distance: 0.113, angle_deg: 0, radius: 0.04125}",
        "  - name: w2",
        f"    {w2_kind}",
        "    distance: 0.113",
        "    angle_deg: 120",
        "    radius: 0.04125",
    ]
    if w2 is not None:
        lines.append(f"    physical: {w2}")
    lines.append("  - {name: w3, type: omni, distance: 0.113, angle_deg: 240, radius: 0.04125}")
    return "\n".join(lines) + "\n"


def write(tmp_path, text: str, name: str = "robot.yaml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def error_of(path) -> str:
    with pytest.raises(RobotFileError) as info:
        load_robot(path)
    message = str(info.value)
    assert "\n" not in message, message
    return message


def line_column(text: str, needle: str, occurrence: int = 1) -> tuple[int, int]:
    """1-based line and column of the ``occurrence``-th ``needle`` in ``text``."""
    at = -1
    for _ in range(occurrence):
        at = text.index(needle, at + 1)
    line = text.count("\n", 0, at) + 1
    return line, at - (text.rfind("\n", 0, at) + 1) + 1


# --- accepted and read back ------------------------------------------------------------------------
ALL_WHEEL = "{width: 0.03, mass: 0.12, rollers: 12, rows: 2, friction: 0.8, max_torque: 0.4}"
ALL_BODY = "{mass: 2.5, com: [0.01, -0.02, 0.06], height: 0.02}"


def test_every_physical_field_is_read_as_written(tmp_path):
    robot = load_robot(write(tmp_path, robot_yaml(ALL_BODY, ALL_WHEEL)))
    assert robot.physical == PhysicalBody(mass=2.5, com=(0.01, -0.02, 0.06), height=0.02)
    w1, w2, w3 = robot.wheels
    assert w2.physical == PhysicalWheel(width=0.03, mass=0.12, rollers=12, rows=2, friction=0.8, max_torque=0.4)
    assert type(w2.physical.rollers) is int and type(w2.physical.rows) is int
    assert w1.physical is None and w3.physical is None


def test_physical_fields_in_json_are_read_as_in_yaml(tmp_path):
    data = {
        "omnikin": 1,
        "name": "phys",
        "physical": {"mass": 2.5, "com": [0.01, -0.02, 0.06], "height": 0.02},
        "wheels": [
            {"name": "w1", "type": "omni", "distance": 0.113, "angle_deg": 0, "radius": 0.04125},
            {
                "name": "w2",
                "type": "omni",
                "distance": 0.113,
                "angle_deg": 120,
                "radius": 0.04125,
                "physical": {"width": 0.03, "mass": 0.12, "rollers": 12, "rows": 2, "friction": 0.8, "max_torque": 0.4},
            },
            {"name": "w3", "type": "omni", "distance": 0.113, "angle_deg": 240, "radius": 0.04125},
        ],
    }
    from_json = load_robot(write(tmp_path, json.dumps(data), "robot.json"))
    from_yaml = load_robot(write(tmp_path, robot_yaml(ALL_BODY, ALL_WHEEL)))
    assert from_json.physical == from_yaml.physical
    assert [w.physical for w in from_json.wheels] == [w.physical for w in from_yaml.wheels]


@pytest.mark.parametrize("field, value", [("width", 0.0001), ("width", 10), ("mass", 1e5), ("friction", 0.001)])
def test_range_bounds_are_accepted(tmp_path, field, value):
    robot = load_robot(write(tmp_path, robot_yaml(w2=f"{{{field}: {value}}}")))
    assert getattr(robot.wheels[1].physical, field) == value


def test_exponent_without_dot_is_read_as_a_number(tmp_path):
    """``5e-2`` is a string in YAML 1.1 but 0.05 in YAML 1.2 and JSON: omnikin reads 0.05."""
    robot = load_robot(write(tmp_path, robot_yaml("{mass: 25e-1}", "{width: 3e-2}")))
    assert robot.wheels[1].physical.width == 0.03 and robot.physical.mass == 2.5


SWEDISH_KEYS = {
    "omni": "type: omni",
    "mecanum": "type: mecanum\n    roller_deg: 45",
    "swedish": "type: swedish\n    roller_deg: 30\n    drive_deg: 210",
}


@pytest.mark.parametrize("kind", list(SWEDISH_KEYS))
def test_rollers_on_every_swedish_wheel(tmp_path, kind):
    robot = load_robot(write(tmp_path, robot_yaml(w2="{rollers: 9, rows: 1}", w2_kind=SWEDISH_KEYS[kind])))
    assert robot.wheels[1].type == kind
    assert robot.wheels[1].physical == PhysicalWheel(rollers=9, rows=1)


@pytest.mark.parametrize("suffix", [".yaml", ".json"])
def test_writer_carries_every_physical_field(tmp_path, suffix):
    robot = load_robot(write(tmp_path, robot_yaml(ALL_BODY, ALL_WHEEL)))
    out = tmp_path / f"saved{suffix}"
    save_robot(robot, out)
    again = load_robot(out)
    assert again.physical == robot.physical
    assert [w.physical for w in again.wheels] == [w.physical for w in robot.wheels]
    data = robot_to_dict(robot)
    assert data["physical"] == {"mass": 2.5, "com": [0.01, -0.02, 0.06], "height": 0.02}
    assert data["wheels"][1]["physical"] == {
        "width": 0.03,
        "mass": 0.12,
        "rollers": 12,
        "rows": 2,
        "friction": 0.8,
        "max_torque": 0.4,
    }


def test_writer_writes_only_the_fields_given(tmp_path):
    robot = load_robot(write(tmp_path, robot_yaml("{height: 0.02}", "{rows: 2}")))
    data = robot_to_dict(robot)
    assert data["physical"] == {"height": 0.02}
    assert data["wheels"][1]["physical"] == {"rows": 2}
    assert "physical" not in data["wheels"][0] and "physical" not in data["wheels"][2]


# --- nothing invented ----------------------------------------------------------------------------
def test_robot_without_physical_fields_loads_unchanged(tmp_path):
    path = write(tmp_path, robot_yaml())
    robot = load_robot(path)
    assert robot.physical is None and all(w.physical is None for w in robot.wheels)
    data = robot_to_dict(robot)
    assert "physical" not in data and all("physical" not in w for w in data["wheels"])
    out = tmp_path / "saved.yaml"
    save_robot(robot, out)
    assert "physical" not in out.read_text(encoding="utf-8")


@pytest.mark.parametrize("name", [n for n in PRESET_NAMES if not n.startswith("tomasi-omni3")])
def test_presets_without_stated_physical_values_have_none(name):
    robot = load_robot(name)
    assert robot.physical is None and all(w.physical is None for w in robot.wheels)
    assert "physical" not in json.dumps(robot_to_dict(robot))


# --- presets ----------------------------------------------------------------------------------------
def test_tomasi_preset_has_the_two_roller_rows_of_its_paper():
    """Tomasi and Todt, Sec. 2.1 and Fig. 2c: "overlapping parallel" VEX omni wheels, two rows
    of rollers. The paper gives no mass, width, roller count, friction or motor torque."""
    robot = load_robot("tomasi-omni3")
    assert [w.physical for w in robot.wheels] == [PhysicalWheel(rows=2)] * 3
    assert robot.physical is None
    assert "Sec. 2.1, Fig. 2c" in robot.description and "NEMA 17" in robot.description


def test_garcia_sillas_preset_says_why_it_has_no_physical_values():
    robot = load_robot("garcia-sillas-omni3")
    assert robot.physical is None and all(w.physical is None for w in robot.wheels)
    assert "states no masses" in robot.description


# --- refused: the file, the wheel and the field, in one line -------------------------------------
W2 = "wheel 'w2' (#2): field"
EMPTY_WHEEL = (
    "is empty: give some of ['width', 'mass', 'rollers', 'rows', 'friction', 'max_torque'], or leave "
    "'physical' out (the physics description then derives every field from the layout)"
)

WHEEL_CASES = [
    # id, text after the wheel's 'physical:', expected message after the file name
    (
        "misspelt-key",
        "{widht: 0.03}",
        f"{W2} 'physical': unknown key(s) ['widht']; allowed: {WHEEL_KEYS}; did you mean 'width'?",
    ),
    ("unknown-key", "{colour: red}", f"{W2} 'physical': unknown key(s) ['colour']; allowed: {WHEEL_KEYS}"),
    ("negative-mass", "{mass: -1}", f"{W2} 'physical.mass': must lie in [0.0001, 100000] kg, got -1"),
    ("zero-mass", "{mass: 0}", f"{W2} 'physical.mass': must lie in [0.0001, 100000] kg, got 0"),
    ("wide-wheel", "{width: 11}", f"{W2} 'physical.width': must lie in [0.0001, 10] m, got 11"),
    ("no-friction", "{friction: 0}", f"{W2} 'physical.friction': must lie in [0.001, 10], got 0"),
    ("huge-torque", "{max_torque: 1e6}", f"{W2} 'physical.max_torque': must lie in [1e-05, 100000] N m, got 1e+06"),
    ("few-rollers", "{rollers: 2}", f"{W2} 'physical.rollers': must be a whole number from 3 to 64, got 2"),
    ("many-rollers", "{rollers: 65}", f"{W2} 'physical.rollers': must be a whole number from 3 to 64, got 65"),
    ("rows-float", "{rows: 2.0}", f"{W2} 'physical.rows': must be a whole number from 1 to 4, got 2.0"),
    ("rows-zero", "{rows: 0}", f"{W2} 'physical.rows': must be a whole number from 1 to 4, got 0"),
    ("rows-bool", "{rows: true}", f"{W2} 'physical.rows': must be a whole number from 1 to 4, got True"),
    ("mass-quoted", "{mass: '0.1'}", f"{W2} 'physical.mass': must be a number, got '0.1'"),
    ("mass-bool", "{mass: true}", f"{W2} 'physical.mass': must be a number, got True"),
    ("mass-list", "{mass: [0.1]}", f"{W2} 'physical.mass': must be a number, got [0.1]"),
    ("width-nan", "{width: .nan}", f"{W2} 'physical.width': must be finite, got nan"),
    ("friction-inf", "{friction: .inf}", f"{W2} 'physical.friction': must be finite, got inf"),
    ("torque-overflow", "{max_torque: 1e999}", f"{W2} 'physical.max_torque': must be finite, got inf"),
    ("empty-mapping", "{}", f"{W2} 'physical': {EMPTY_WHEEL}"),
    ("empty-value", "", f"{W2} 'physical': {EMPTY_WHEEL}"),
    (
        "a-list",
        "[0.03, 0.1]",
        f"{W2} 'physical': must be a mapping with some of the keys ['width', 'mass', 'rollers', 'rows', "
        f"'friction', 'max_torque'], got [0.03, 0.1]",
    ),
    (
        "a-number",
        "0.03",
        f"{W2} 'physical': must be a mapping with some of the keys ['width', 'mass', 'rollers', 'rows', "
        f"'friction', 'max_torque'], got 0.03",
    ),
]


@pytest.mark.parametrize("physical, expected", [c[1:] for c in WHEEL_CASES], ids=[c[0] for c in WHEEL_CASES])
def test_bad_wheel_physical_field_names_file_wheel_and_field(tmp_path, physical, expected):
    path = write(tmp_path, robot_yaml(w2=physical))
    assert error_of(path) == f"{path}: {expected}"


BODY_CASES = [
    (
        "misspelt-key",
        "{mas: 1}",
        f"field 'physical': unknown key(s) ['mas']; allowed: {BODY_KEYS}; did you mean 'mass'?",
    ),
    ("zero-mass", "{mass: 0}", "field 'physical.mass': must lie in [0.0001, 100000] kg, got 0"),
    ("flat-chassis", "{height: 0}", "field 'physical.height': must lie in [0.001, 10] m, got 0"),
    ("com-two", "{com: [0, 0]}", "field 'physical.com': must be a list of 3 numbers [x, y, z] in m, got [0, 0]"),
    ("com-text", "{com: '0 0 0.1'}", "field 'physical.com': must be a list of 3 numbers [x, y, z] in m, got '0 0 0.1'"),
    (
        "com-mapping",
        "{com: {z: 0.1}}",
        "field 'physical.com': must be a list of 3 numbers [x, y, z] in m, got {'z': 0.1}",
    ),
    ("com-under-floor", "{com: [0, 0, -0.1]}", "field 'physical.com.z': must lie in [0.0001, 1000] m, got -0.1"),
    ("com-on-floor", "{com: [0, 0, 0]}", "field 'physical.com.z': must lie in [0.0001, 1000] m, got 0"),
    ("com-far", "{com: [1e4, 0, 0.1]}", "field 'physical.com.x': must lie in [-1000, 1000] m, got 10000"),
    ("com-null", "{com: [0, null, 0.1]}", "field 'physical.com.y': must be a number, got None"),
    (
        "empty",
        "{}",
        "field 'physical': is empty: give some of ['mass', 'com', 'height'], or leave 'physical' out "
        "(the physics description then derives every field from the layout)",
    ),
    ("a-number", "2.5", "field 'physical': must be a mapping with some of the keys ['mass', 'com', 'height'], got 2.5"),
]


@pytest.mark.parametrize("physical, expected", [c[1:] for c in BODY_CASES], ids=[c[0] for c in BODY_CASES])
def test_bad_body_physical_field_names_file_and_field(tmp_path, physical, expected):
    path = write(tmp_path, robot_yaml(top=physical))
    assert error_of(path) == f"{path}: {expected}"


CASTOR = "type: castor\n    drive_deg: 0\n    steer: {offset: 0.02}"
NO_ROLLERS = {
    "standard": "type: standard\n    drive_deg: 0",
    "steerable": "type: steerable\n    drive_deg: 0",
    "castor": CASTOR,
}


@pytest.mark.parametrize("kind", list(NO_ROLLERS))
@pytest.mark.parametrize("field", ["rollers", "rows"])
def test_rollers_on_a_wheel_without_rollers_are_refused(tmp_path, kind, field):
    path = write(tmp_path, robot_yaml(w2=f"{{{field}: 3}}", w2_kind=NO_ROLLERS[kind]))
    assert error_of(path) == (
        f"{path}: {W2} 'physical.{field}': only Swedish wheels (omni, mecanum, swedish) have rollers, not '{kind}'"
    )


def test_motor_torque_on_a_castor_is_refused(tmp_path):
    path = write(tmp_path, robot_yaml(w2="{max_torque: 0.5}", w2_kind=CASTOR))
    assert error_of(path) == f"{path}: {W2} 'physical.max_torque': a castor is passive: it has no motor"


def test_castor_may_have_a_mass_and_width(tmp_path):
    text = robot_yaml(w2="{mass: 0.05, width: 0.02}", w2_kind=CASTOR)
    text += "  - {name: w4, type: omni, distance: 0.113, angle_deg: 60, radius: 0.04125}\n"  # three rolling wheels
    robot = load_robot(write(tmp_path, text))
    assert robot.wheels[1].physical == PhysicalWheel(mass=0.05, width=0.02)


def test_json_physical_errors_read_as_yaml_ones(tmp_path):
    data = {
        "omnikin": 1,
        "name": "phys",
        "physical": {"mass": 2.5, "com": [0, 0, 0.1], "height": -1},
        "wheels": [
            {"name": f"w{i + 1}", "type": "omni", "distance": 0.113, "angle_deg": a, "radius": 0.04125}
            for i, a in enumerate((0, 120, 240))
        ],
    }
    path = write(tmp_path, json.dumps(data), "robot.json")
    assert error_of(path) == f"{path}: field 'physical.height': must lie in [0.001, 10] m, got -1"
    text = json.dumps(data).replace('"height": -1', '"mass": 3')
    path = write(tmp_path, text, "dup.json")
    assert error_of(path) == f"{path}: duplicate key 'mass'"


# --- YAML oddities: the line and the column --------------------------------------------------------
@pytest.mark.parametrize(
    "top, w2, literal, problem",
    [
        (None, "{rows: 02}", "02", "02 is octal in YAML 1.1 (2) but decimal in YAML 1.2: write 2, not 02"),
        (
            "{mass: 0x10}",
            None,
            "0x10",
            "0x10 is a hexadecimal number in YAML 1.1 (16), not a plain decimal: write 16, not 0x10",
        ),
        (
            None,
            "{max_torque: 1_000}",
            "1_000",
            "1_000 has digit separators (_), one number in YAML 1.1 only (1000): write 1000, not 1_000",
        ),
        (
            None,
            "{rollers: 1:30}",
            "1:30",
            "1:30 is a base-60 (sexagesimal) number in YAML 1.1 (90) but text in YAML 1.2: write 90, not 1:30",
        ),
        (
            "{com: [0, 0, 0b1]}",
            None,
            "0b1",
            "0b1 is a binary number in YAML 1.1 (1), not a plain decimal: write 1, not 0b1",
        ),
    ],
)
def test_yaml_number_forms_in_physical_fields_name_line_and_column(tmp_path, top, w2, literal, problem):
    text = robot_yaml(top, w2)
    line, column = line_column(text, literal)
    path = write(tmp_path, text)
    assert error_of(path) == f"{path}: line {line} column {column}: {problem}"


def test_anchor_in_physical_is_refused_with_its_line(tmp_path):
    text = robot_yaml(w2="&p {rows: 2}")
    path = write(tmp_path, text)
    line, column = line_column(text, "&p")
    message = error_of(path)
    assert message.startswith(f"{path}: invalid YAML at line {line} column {column}: anchors (&name) and aliases")


def test_duplicate_physical_key_is_refused_with_its_line(tmp_path):
    text = robot_yaml(w2="{rows: 2, width: 0.03, rows: 3}")
    path = write(tmp_path, text)
    line, column = line_column(text, "rows", occurrence=2)
    assert error_of(path) == f"{path}: invalid YAML at line {line} column {column}: duplicate key 'rows'"


def test_huge_unknown_physical_key_gives_a_short_message(tmp_path):
    """A 200 000-character key (JSON allows it; YAML refuses implicit keys over 1024 characters)
    is quoted shortened, and no close match is looked for."""
    wheels = [
        {"name": f"w{i + 1}", "type": "omni", "distance": 0.113, "angle_deg": a, "radius": 0.04125}
        for i, a in enumerate((0, 120, 240))
    ]
    wheels[1]["physical"] = {"k" * 200_000: 1}
    path = write(tmp_path, json.dumps({"omnikin": 1, "name": "phys", "wheels": wheels}), "robot.json")
    message = error_of(path)
    assert message.startswith(f"{path}: {W2} 'physical': unknown key(s) ['kkkk") and len(message) < 500
