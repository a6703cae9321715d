"""Mobility analysis against Campion, Bastin and d'Andrea-Novel (1996), Table 1 / Sec. 3."""

import json
import math

import numpy as np
import pytest

from omnikin import PRESET_NAMES, Robot, SingularLayoutError, Steer, Wheel, load_robot
from omnikin.kinematics.mobility import CONDITION_WARNING
from support.kinematics import omni_robot

CASTOR = dict(steer=Steer(offset=0.03))


def castor(name, x, y):
    return Wheel(name, "castor", x, y, 0.0, 0.03, **CASTOR)


@pytest.mark.parametrize(
    "name, campion, holonomic",
    [
        ("tomasi-omni3", (3, 0), True),
        ("garcia-sillas-omni3", (3, 0), True),
        ("omni4", (3, 0), True),
        ("mecanum4", (3, 0), True),
        ("xr4000", (3, 0), True),  # powered castors do not constrain the body
        ("villasenor-omni3", (3, 0), True),
        ("diff-drive", (2, 0), False),
        ("ackermann", (1, 1), False),
        ("synchro", (1, 2), False),  # steering coupling not expressible in schema 1
    ],
)
def test_presets_campion_types(name, campion, holonomic):
    m = load_robot(name).mobility
    assert m.campion_type == campion
    assert m.holonomic is holonomic


def test_type_2_1_one_centred_steerable_wheel_and_castors():
    robot = Robot(
        "2-1", (Wheel("s", "steerable", 0.3, 0.0, 0.0, 0.1), castor("c1", -0.2, 0.2), castor("c2", -0.2, -0.2))
    )
    assert robot.mobility.campion_type == (2, 1)
    # spinning about the steered wheel's contact is done by steering alone: odometry from wheel
    # speeds cannot see it, and says so
    with pytest.raises(SingularLayoutError, match="steering alone"):
        robot.check_observable(["s"])


def test_type_1_2_two_centred_steerable_wheels():
    robot = Robot(
        "1-2",
        (
            Wheel("s1", "steerable", 0.3, 0.0, 0.0, 0.1),
            Wheel("s2", "steerable", -0.3, 0.0, 0.0, 0.1),
            castor("c", 0.0, 0.3),
        ),
    )
    assert robot.mobility.campion_type == (1, 2)


def test_fixed_wheels_with_radial_axles_can_only_spin():
    """Axles all through the origin (tangent drive): the only motion is rotation about it, (1, 0)."""
    wheels = tuple(
        Wheel(f"w{i}", "standard", 0.2 * math.cos(b), 0.2 * math.sin(b), b + math.pi / 2, 0.05)
        for i, b in enumerate(np.radians([0, 120, 240]))
    )
    m = Robot("spinner", wheels).mobility
    assert m.campion_type == (1, 0)
    assert "degenerate" in m.campion_name


def test_tricycle_is_car_like():
    robot = Robot(
        "tricycle",
        (
            Wheel("l", "standard", 0, 0.2, 0.0, 0.1),
            Wheel("r", "standard", 0, -0.2, 0.0, 0.1),
            Wheel("f", "steerable", 0.5, 0.0, 0.0, 0.1),
        ),
    )
    assert robot.mobility.campion_type == (1, 1)


def test_symmetric_omni3_is_isotropic_with_closed_form_length(tomasi):
    """J^T J = diag(3/2, 3/2, 3 l^2) / r^2: isotropic with L = sqrt(2) l (Angeles' characteristic length)."""
    m = tomasi.mobility
    assert m.isotropic
    assert m.condition_number == pytest.approx(1.0, abs=1e-12)
    assert m.characteristic_length == pytest.approx(math.sqrt(2) * 0.113, rel=1e-12)
    assert m.rank == 3


def test_unequal_spacing_is_not_isotropic():
    m = omni_robot([0, 90, 200]).mobility
    assert not m.isotropic and m.condition_number > 1.01


def test_radial_drive_directions_are_singular():
    """Drive directions pointing at the centre: a spin turns no wheel."""
    with pytest.raises(SingularLayoutError, match=r"rotation about the point \(0, 0\)"):
        omni_robot([0, 120, 240], drive_offsets_deg=[-90, -90, -90])


def test_concurrent_drive_lines_name_the_point():
    """All three drive lines through (0.1, 0): rotation about that point is invisible."""
    wheels = []
    for i, (x, y) in enumerate([(0.4, 0.0), (-0.2, 0.3), (-0.2, -0.3)]):
        wheels.append(Wheel(f"w{i}", "omni", x, y, math.atan2(y, x - 0.1), 0.05))
    with pytest.raises(SingularLayoutError, match=r"rotation about the point \(0\.1, 0\)"):
        Robot("concurrent", tuple(wheels))


def test_two_omni_wheels_cannot_measure_every_motion():
    with pytest.raises(SingularLayoutError, match="rank 2 < 3"):
        omni_robot([0, 180])


def test_parallel_rollers_cannot_see_a_translation():
    """Four mecanum wheels with the same roller sign: lateral translation along the rollers' free
    direction is invisible."""
    wheels = tuple(
        Wheel(n, "mecanum", x, y, 0.0, 0.05, math.radians(45))
        for n, x, y in [("a", 0.2, 0.2), ("b", 0.2, -0.2), ("c", -0.2, 0.2), ("d", -0.2, -0.2)]
    )
    with pytest.raises(SingularLayoutError, match="translation along"):
        Robot("bad-mecanum", wheels)


def test_three_fixed_wheels_with_tangent_axles_are_immobile():
    """Axles along the tangents (drive directions radial) share no instantaneous centre."""
    wheels = tuple(
        Wheel(f"w{i}", "standard", 0.2 * math.cos(b), 0.2 * math.sin(b), b, 0.05)
        for i, b in enumerate(np.radians([0, 120, 240]))
    )
    with pytest.raises(SingularLayoutError, match="immobile"):
        Robot("locked", wheels)


def test_castors_alone_are_rejected():
    with pytest.raises(SingularLayoutError, match="no rolling wheel"):
        Robot("castors", (castor("a", 0.1, 0), castor("b", -0.1, 0)))


# --- conditioning warning (threshold 10, docs/conventions.md "Conditioning") ------------------------------------
SKEWED = (
    "omnikin: 1\nname: skewed-omni3\nwheels:\n"
    "  - {name: a, type: omni, x: 0.2, y: 0.1, drive_deg: 0, radius: 0.05}\n"
    "  - {name: b, type: omni, x: 0.2, y: -0.1, drive_deg: 0, radius: 0.05}\n"
    "  - {name: c, type: omni, x: -0.2, y: 0.0, drive_deg: 10, radius: 0.05}\n"
)


def skewed_condition_by_hand() -> float:
    """Rows (cos d, sin d, x sin d - y cos d) / r typed in; not isotropic (J^T J has unequal translational
    diagonal), so the rotation is scaled by the RMS wheel distance L (omnikin.kinematics.mobility docstring)."""
    r = 0.05
    d = math.radians(10)
    jac = np.array([[1, 0, -0.1], [1, 0, 0.1], [math.cos(d), math.sin(d), -0.2 * math.sin(d)]]) / r
    length = math.sqrt((0.05 + 0.05 + 0.04) / 3)
    s = np.linalg.svd(jac @ np.diag([1, 1, 1 / length]), compute_uv=False)
    return s[0] / s[-1]


def test_badly_conditioned_layout_is_flagged(tmp_path):
    path = tmp_path / "skewed.yaml"
    path.write_text(SKEWED)
    m = load_robot(path).mobility
    assert m.condition_number == pytest.approx(skewed_condition_by_hand(), rel=1e-9)
    assert m.condition_number > CONDITION_WARNING == 10.0
    assert not m.well_conditioned and f"{m.condition_number:.3g}" in m.conditioning_warning


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_presets_are_well_conditioned(name):
    m = load_robot(name).mobility
    assert m.well_conditioned and m.conditioning_warning is None and m.condition_number < 5


def test_show_warns_once_on_stderr_and_in_json(tmp_path, capsys):
    from omnikin.cli.main import main

    path = tmp_path / "skewed.yaml"
    path.write_text(SKEWED)
    assert main(["show", str(path), "--json"]) == 0
    out, err = capsys.readouterr()
    doc = json.loads(out)
    assert doc["condition_warning"] and "badly conditioned" in doc["condition_warning"]
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("omnikin: warning: skewed-omni3: badly conditioned")
    assert main(["show", str(path)]) == 0
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    assert main(["show", "tomasi-omni3", "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["condition_warning"] is None and err == ""
