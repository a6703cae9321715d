"""The ``omnikin`` command line: every command on every preset, and bad input.

Expected numbers come from closed forms typed in here (docs/conventions.md) and from
the preset YAML files read with PyYAML, never from omnikin's own computations.
Most cases run in-process through ``omnikin.cli.main.main(argv)``; a handful run the
real entry point in a subprocess (help texts, tracebacks).
"""

from __future__ import annotations

import json
import math
import shutil
import subprocess

import numpy as np
import pytest
import yaml

import omnikin
from omnikin import PRESET_NAMES
from omnikin.presets import preset_path
from support.cli import run_cli as cli
from support.cli import run_entry_point

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
COMMANDS = ("presets", "show", "ik", "fk", "odometry")
STEERABLE_PRESETS = ("villasenor-omni3", "ackermann", "synchro", "xr4000")
SWEDISH_PRESETS = ("tomasi-omni3", "tomasi-omni3-lidar", "garcia-sillas-omni3", "mecanum4", "omni4")
# Campion types known from the layouts (Campion, Bastin, d'Andrea-Novel 1996)
CAMPION = {
    "tomasi-omni3": (3, 0),
    "tomasi-omni3-lidar": (3, 0),
    "garcia-sillas-omni3": (3, 0),
    "villasenor-omni3": (3, 0),
    "diff-drive": (2, 0),
    "ackermann": (1, 1),
    "synchro": (1, 2),
    "xr4000": (3, 0),
    "mecanum4": (3, 0),
    "omni4": (3, 0),
}
# a feasible twist with some rotation for each preset
FEASIBLE = {name: (0.1, 0.05, 0.2) for name in PRESET_NAMES}
FEASIBLE.update({"diff-drive": (0.1, 0.0, 0.2), "ackermann": (1.0, 0.0, 0.3)})


# --- independent model of the presets ---------------------------------------------------------------
def preset_wheels(name):
    """Rolling wheels of a preset read straight from its YAML: (name, type, x, y, drive, gamma, r, offset)."""
    data = yaml.safe_load(preset_path(name).read_text(encoding="utf-8"))
    out = []
    for w in data["wheels"]:
        if w["type"] == "castor":
            continue
        if "x" in w:
            x, y = float(w["x"]), float(w["y"])
        else:
            b = math.radians(w["angle_deg"])
            x, y = w["distance"] * math.cos(b), w["distance"] * math.sin(b)
        drive = math.radians(w["drive_deg"]) if "drive_deg" in w else math.atan2(y, x) + math.pi / 2
        gamma = math.radians(w.get("roller_deg", 0.0))
        offset = w.get("steer", {}).get("offset", 0.0)
        out.append((w["name"], w["type"], x, y, drive, gamma, float(w["radius"]), offset))
    return out


def hand_row(x, y, delta, r, gamma=0.0):
    """docs/conventions.md: omega_i = [cos a vx + sin a vy + (x sin a - y cos a) omega] / (r cos gamma)."""
    a = delta + gamma
    return np.array([math.cos(a), math.sin(a), x * math.sin(a) - y * math.cos(a)]) / (r * math.cos(gamma))


def hand_J(name):
    return np.array([hand_row(x, y, d, r, g) for _, _, x, y, d, g, r, _ in preset_wheels(name)])


# --- running the CLI -------------------------------------------------------------------------------------


def cli_json(capsys, *argv):
    rc, out, err = cli(capsys, *argv, "--json")
    assert rc == 0, err
    assert err == ""
    return json.loads(out)


run = run_entry_point  # the real entry point in a subprocess, this checkout's omnikin from any folder


def assert_clean_error(rc, err, *fragments):
    """Exit 2, one line 'omnikin: error: ...' on stderr, no traceback."""
    assert rc == 2
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("omnikin: error: "), err
    for f in fragments:
        assert f in lines[0], (f, err)
    return lines[0]


# --- help, version ------------------------------------------------------------------------------------
def test_top_level_help_subprocess():
    proc = run("--help")
    assert proc.returncode == 0 and proc.stderr == ""
    assert "example" in proc.stdout.lower()
    for cmd in COMMANDS:
        assert cmd in proc.stdout


@pytest.mark.parametrize("cmd", COMMANDS)
def test_subcommand_help_mentions_examples(cmd):
    proc = run(cmd, "--help")
    assert proc.returncode == 0 and proc.stderr == ""
    assert proc.stdout.startswith(f"usage: omnikin {cmd}")
    assert "example" in proc.stdout.lower()


@pytest.mark.parametrize("cmd", COMMANDS)
def test_subcommand_help_in_process(capsys, cmd):
    rc, out, err = cli(capsys, cmd, "--help")
    assert rc == 0 and f"omnikin {cmd}" in out and err == ""


def test_installed_script_runs():
    exe = shutil.which("omnikin")
    if exe is None:
        pytest.skip("omnikin console script not on PATH")
    proc = subprocess.run(
        [exe, "ik", "tomasi-omni3", "0", "0", "1", "--json"], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
    np.testing.assert_allclose(json.loads(proc.stdout)["wheel_speeds"], [0.113 / 0.04125] * 3, rtol=1e-12)


def test_version(capsys):
    rc, out, _ = cli(capsys, "--version")
    assert rc == 0 and omnikin.__version__ in out


def test_no_command_prints_help_and_fails(capsys):
    rc, out, _ = cli(capsys)
    assert rc == 2 and "usage: omnikin" in out


# --- presets ---------------------------------------------------------------------------------------------
def test_presets_text(capsys):
    rc, out, err = cli(capsys, "presets")
    assert rc == 0 and err == ""
    for name in PRESET_NAMES:
        assert name in out


def test_presets_json(capsys):
    data = cli_json(capsys, "presets")
    assert [d["name"] for d in data] == list(PRESET_NAMES)
    for d in data:
        assert tuple(d["campion_type"]) == CAMPION[d["name"]]
        raw = yaml.safe_load(preset_path(d["name"]).read_text(encoding="utf-8"))
        assert d["wheels"] == len(raw["wheels"])
        assert d["holonomic"] == (CAMPION[d["name"]] == (3, 0))


# --- show ---------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", PRESET_NAMES)
def test_show_text(capsys, name):
    rc, out, err = cli(capsys, "show", name)
    assert rc == 0 and err == ""
    assert name in out and "Campion" in out
    for w in preset_wheels(name):
        assert w[0] in out


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_show_json(capsys, name):
    data = cli_json(capsys, "show", name)
    for key in ("ik_matrix", "rank", "mobility", "steerability"):
        assert key in data
    n = len(preset_wheels(name))
    ik = np.array(data["ik_matrix"])
    assert ik.shape == (n, 3)
    assert np.array(data["fk_matrix"]).shape == (3, n)
    # the IK matrix at zero steering is the stack of hand-derived rolling rows
    np.testing.assert_allclose(ik, hand_J(name), atol=1e-9)
    assert isinstance(data["rank"], int) and 1 <= data["rank"] <= 3
    assert (data["mobility"], data["steerability"]) == CAMPION[name]
    assert data["wheel_names"] == [w[0] for w in preset_wheels(name)]
    if name in SWEDISH_PRESETS:
        assert data["rank"] == 3 == np.linalg.matrix_rank(hand_J(name))
    if name == "diff-drive":
        assert data["rank"] == 2


def test_show_json_file_robot(capsys, tmp_path):
    """ROBOT may be a file path; the IK matrix follows the file."""
    path = tmp_path / "tri.yaml"
    path.write_text(
        "omnikin: 1\nname: tri\nwheels:\n"
        "  - {name: a, type: omni, distance: 0.2, angle_deg: 90, radius: 0.05}\n"
        "  - {name: b, type: omni, distance: 0.2, angle_deg: 210, radius: 0.05}\n"
        "  - {name: c, type: omni, distance: 0.2, angle_deg: 330, radius: 0.05}\n",
        encoding="utf-8",
    )
    data = cli_json(capsys, "show", path)
    expected = [
        [-math.sin(math.radians(b)) / 0.05, math.cos(math.radians(b)) / 0.05, 0.2 / 0.05] for b in (90, 210, 330)
    ]
    np.testing.assert_allclose(data["ik_matrix"], expected, atol=1e-12)


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_show_plot_writes_png(capsys, tmp_path, name):
    out_png = tmp_path / f"{name}.png"
    rc, out, err = cli(capsys, "show", name, "--plot", out_png)
    assert rc == 0, err
    data = out_png.read_bytes()
    assert len(data) > 1000 and data[:8] == PNG_MAGIC
    assert out_png.name in out


def test_show_plot_with_json(capsys, tmp_path):
    out_png = tmp_path / "t.png"
    data = cli_json(capsys, "show", "omni4", "--plot", out_png)
    assert data["name"] == "omni4"
    assert out_png.read_bytes()[:8] == PNG_MAGIC


def test_show_plot_unwritable_path(capsys, tmp_path):
    """--plot into a missing directory: one-line error, no FileNotFoundError traceback."""
    rc, _, err = cli(capsys, "show", "tomasi-omni3", "--plot", tmp_path / "no" / "such" / "dir.png")
    assert_clean_error(rc, err, "dir.png")


def test_show_plot_unknown_format(capsys, tmp_path):
    """--plot layout.xyz: matplotlib's ValueError for the extension must not escape as a traceback."""
    rc, _, err = cli(capsys, "show", "tomasi-omni3", "--plot", tmp_path / "layout.xyz")
    assert_clean_error(rc, err, "xyz")


# --- ik ---------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", PRESET_NAMES)
def test_ik_every_preset_forward_twist(capsys, name):
    twist = np.array([0.1, 0.0, 0.0])
    data = cli_json(capsys, "ik", name, *twist)
    wheels = preset_wheels(name)
    speeds = np.array(data["wheel_speeds"])
    assert speeds.shape == (len(wheels),)
    assert data["wheel_names"] == [w[0] for w in wheels]
    np.testing.assert_allclose(data["twist"], twist)
    if name in STEERABLE_PRESETS:
        steer_names = [w[0] for w in wheels if w[1] == "steerable"]
        assert data["steer_names"] == steer_names
        steer = dict(zip(steer_names, data["steer_angles"], strict=True))
        assert len(data["steer_angles"]) == len(steer_names)
        for (wname, _kind, _x, _y, drive, _, r, _), w_speed in zip(wheels, speeds, strict=True):
            delta = drive + steer.get(wname, 0.0)
            # pure translation along x: every hub moves along +x, so each steered wheel lies along x
            # and rolls at cos(delta) * 0.1 / r
            assert math.sin(delta) == pytest.approx(0.0, abs=1e-9)
            assert w_speed == pytest.approx(math.cos(delta) * 0.1 / r, rel=1e-9)
    else:
        assert "steer_angles" not in data
        np.testing.assert_allclose(speeds, hand_J(name) @ twist, atol=1e-9)


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_ik_every_preset_turning_twist(capsys, name):
    twist = np.array(FEASIBLE[name])
    data = cli_json(capsys, "ik", name, *twist)
    wheels = preset_wheels(name)
    speeds = np.array(data["wheel_speeds"])
    steer = dict(zip(data.get("steer_names", []), data.get("steer_angles", []), strict=True))
    for (wname, kind, x, y, drive, gamma, r, offset), w_speed in zip(wheels, speeds, strict=True):
        delta = drive + steer.get(wname, 0.0)
        vp = np.array([twist[0] - twist[2] * y, twist[1] + twist[2] * x])  # hub (steering axis) velocity
        if kind == "steerable":
            n = np.array([-math.sin(delta), math.cos(delta)])
            # steady swivel: n . v_p = offset * omega (centred: no side slip)
            assert n @ vp == pytest.approx(offset * twist[2], abs=1e-9)
        # rolling: conventions' row at the steering axis point
        assert w_speed == pytest.approx(hand_row(x, y, delta, r, gamma) @ twist, abs=1e-9)
    if "feasible" in data:
        assert data["feasible"] is True


def test_ik_tomasi_pure_rotation(capsys):
    data = cli_json(capsys, "ik", "tomasi-omni3", 0, 0, 1)
    np.testing.assert_allclose(data["wheel_speeds"], [0.113 / 0.04125] * 3, rtol=1e-12)


@pytest.mark.parametrize("twist", [(0.2, 0.0, 0.5), (0.0, 0.3, 0.0), (-0.1, 0.25, -1.5), (1.0, 0.0, 0.0)])
def test_ik_tomasi_closed_form(capsys, twist):
    vx, vy, w = twist
    lever, r = 0.113, 0.04125
    expected = [(-math.sin(b) * vx + math.cos(b) * vy + lever * w) / r for b in np.radians([0, 120, 240])]
    data = cli_json(capsys, "ik", "tomasi-omni3", vx, vy, w)
    np.testing.assert_allclose(data["wheel_speeds"], expected, rtol=1e-12, atol=1e-12)
    # rollers of omni wheels carry the hub velocity along the axle; omnikin counts it positive along
    # n = (-sin(delta), cos(delta)) = -(cos b, sin b) for delta = b + 90 deg (model.roller_speeds)
    rollers = [-(math.cos(b) * vx + math.sin(b) * vy) for b in np.radians([0, 120, 240])]
    np.testing.assert_allclose(data["roller_speeds"], rollers, atol=1e-12)


def test_ik_tomasi_text_output(capsys):
    rc, out, err = cli(capsys, "ik", "tomasi-omni3", 0, 0, 1)
    assert rc == 0 and err == ""
    assert out.count(f"{0.113 / 0.04125:.6g}") == 3


@pytest.mark.parametrize("v, w", [(0.5, 0.0), (0.0, 1.0), (0.3, -0.8), (-0.2, 0.4)])
def test_ik_diff_drive_closed_form(capsys, v, w):
    r, half = 0.0825, 0.165
    data = cli_json(capsys, "ik", "diff-drive", v, 0, w)
    assert data["wheel_names"] == ["left", "right"]
    np.testing.assert_allclose(data["wheel_speeds"], [(v - half * w) / r, (v + half * w) / r], atol=1e-12)
    assert data["feasible"] is True
    np.testing.assert_allclose(data["violation"], [0.0, 0.0], atol=1e-12)


def test_ik_ackermann_closed_form(capsys):
    v, w, d, half, r = 1.0, 0.3, 0.6, 0.25, 0.1
    data = cli_json(capsys, "ik", "ackermann", v, 0, w)
    assert data["steer_names"] == ["front_left", "front_right"]
    np.testing.assert_allclose(
        data["steer_angles"], [math.atan2(d * w, v - half * w), math.atan2(d * w, v + half * w)], atol=1e-12
    )
    np.testing.assert_allclose(
        data["wheel_speeds"],
        [
            (v - half * w) / r,
            (v + half * w) / r,
            math.hypot(v - half * w, d * w) / r,
            math.hypot(v + half * w, d * w) / r,
        ],
        atol=1e-12,
    )
    assert data["feasible"] is True


def test_ik_synchro_parallel_steering(capsys):
    """omega = 0: all three wheels steer to the direction of travel and roll at |v| / r."""
    data = cli_json(capsys, "ik", "synchro", 0.1, 0.1, 0)
    np.testing.assert_allclose(data["steer_angles"], [math.pi / 4] * 3, atol=1e-12)
    np.testing.assert_allclose(data["wheel_speeds"], [math.hypot(0.1, 0.1) / 0.05] * 3, atol=1e-12)


def test_ik_heading_world_frame(capsys):
    """World velocity (1, 0) at heading pi/2 is body velocity (0, -1)."""
    data = cli_json(capsys, "ik", "tomasi-omni3", 1, 0, 0, "--heading", math.pi / 2)
    np.testing.assert_allclose(data["twist"], [0.0, -1.0, 0.0], atol=1e-12)
    expected = [(-math.cos(b)) / 0.04125 for b in np.radians([0, 120, 240])]
    np.testing.assert_allclose(data["wheel_speeds"], expected, atol=1e-9)


def test_ik_steer_hint_chooses_reversed_branch(capsys):
    """xr4000 can also reach a forward twist with every wheel turned round (steer 180, speed negative)."""
    data = cli_json(capsys, "ik", "xr4000", 0.1, 0, 0, "--steer-hint-deg", 170, 170, 170, 170)
    for a, s in zip(data["steer_angles"], data["wheel_speeds"], strict=True):
        assert abs(math.cos(a) + 1) < 1e-9
        assert s == pytest.approx(-0.1 / 0.05)


# --- fk ------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", [n for n in PRESET_NAMES if n not in STEERABLE_PRESETS])
def test_fk_every_unsteered_preset_recovers_twist(capsys, name):
    twist = np.array(FEASIBLE[name])
    speeds = hand_J(name) @ twist
    data = cli_json(capsys, "fk", name, *speeds)
    np.testing.assert_allclose(data["twist"], twist, atol=1e-9)
    assert data["residual_norm"] == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_fk_of_ik_output_gives_back_twist(capsys, name):
    twist = FEASIBLE[name]
    ik = cli_json(capsys, "ik", name, *twist)
    argv = ["fk", name, *ik["wheel_speeds"]]
    if "steer_angles" in ik:
        argv += ["--steer-deg", *np.degrees(ik["steer_angles"])]
    fk = cli_json(capsys, *argv)
    np.testing.assert_allclose(fk["twist"], twist, atol=1e-7)
    assert fk["residual_norm"] < 1e-6


def test_fk_diff_drive_closed_form(capsys):
    r, half, wl, wr = 0.0825, 0.165, 3.0, 5.0
    data = cli_json(capsys, "fk", "diff-drive", wl, wr)
    np.testing.assert_allclose(data["twist"], [r * (wl + wr) / 2, 0.0, r * (wr - wl) / (2 * half)], atol=1e-12)


def test_fk_synchro_steered_30_deg(capsys):
    """All wheels at 30 deg rolling at 4 rad/s: translation of 0.2 m/s along 30 deg."""
    data = cli_json(capsys, "fk", "synchro", 4, 4, 4, "--steer-deg", 30, 30, 30)
    v = 4 * 0.05
    np.testing.assert_allclose(data["twist"], [v * math.cos(math.pi / 6), v * math.sin(math.pi / 6), 0], atol=1e-12)


def test_fk_ackermann_closed_form(capsys):
    v, w, d, half, r = 1.0, 0.3, 0.6, 0.25, 0.1
    speeds = [
        (v - half * w) / r,
        (v + half * w) / r,
        math.hypot(v - half * w, d * w) / r,
        math.hypot(v + half * w, d * w) / r,
    ]
    steer = [math.degrees(math.atan2(d * w, v - half * w)), math.degrees(math.atan2(d * w, v + half * w))]
    data = cli_json(capsys, "fk", "ackermann", *speeds, "--steer-deg", *steer)
    np.testing.assert_allclose(data["twist"], [v, 0, w], atol=1e-9)


def test_fk_omni4_least_squares_residual(capsys):
    """Redundant layout: FK is the least-squares twist, the residual what it cannot explain."""
    speeds = np.array([10.0, 0.0, 0.0, 0.0])
    J = hand_J("omni4")
    twist, *_ = np.linalg.lstsq(J, speeds, rcond=None)
    data = cli_json(capsys, "fk", "omni4", *speeds)
    np.testing.assert_allclose(data["twist"], twist, atol=1e-9)
    np.testing.assert_allclose(data["residual"], speeds - J @ twist, atol=1e-9)
    assert data["residual_norm"] == pytest.approx(np.linalg.norm(speeds - J @ twist), abs=1e-9)
    assert data["residual_norm"] > 1.0  # these speeds are inconsistent (slip)


def test_fk_text_output(capsys):
    rc, out, err = cli(capsys, "fk", "diff-drive", 3, 5)
    assert rc == 0 and err == "" and "vx=" in out and "residual" in out


# --- bad input (in-process; main must return 2, never raise) ----------------------------------------------------
def test_unknown_robot(capsys):
    for argv in (
        ("show", "no-such-bot"),
        ("ik", "no-such-bot", 0, 0, 0),
        ("fk", "no-such-bot", 1),
        ("odometry", "no-such-bot", "log.csv", "-o", "out.csv"),
    ):
        rc, _, err = cli(capsys, *argv)
        line = assert_clean_error(rc, err, "no-such-bot")
        for name in PRESET_NAMES:
            assert name in line


def test_bad_robot_file_names_file(capsys, tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(
        "omnikin: 1\nname: bad\nwheels:\n  - {name: w1, type: omni, distance: 0.1, angle_deg: 0, radius: -0.04}\n",
        encoding="utf-8",
    )
    rc, _, err = cli(capsys, "show", path)
    assert_clean_error(rc, err, str(path), "'w1'", "'radius'")


@pytest.mark.parametrize(
    "name, count", [("tomasi-omni3", 2), ("tomasi-omni3", 4), ("omni4", 3), ("diff-drive", 3), ("synchro", 1)]
)
def test_fk_wrong_number_of_speeds(capsys, name, count):
    n = len(preset_wheels(name))
    rc, _, err = cli(capsys, "fk", name, *([1.0] * count))
    assert_clean_error(rc, err, f"{n} wheel speeds", f"got {count}")


@pytest.mark.parametrize(
    "argv",
    [
        ("ik", "tomasi-omni3", "fast", 0, 0),
        ("ik", "tomasi-omni3", 0, 0, "1rad"),
        ("fk", "tomasi-omni3", 1, "two", 3),
        ("ik", "tomasi-omni3", 0, 0),
        ("odometry", "tomasi-omni3", "log.csv", "-o", "x", "--counter-bits", "16.5"),
    ],
)
def test_non_numeric_or_missing_arguments(capsys, argv):
    rc, out, err = cli(capsys, *argv)
    assert rc == 2 and out == ""
    assert "Traceback" not in err and "error:" in err


@pytest.mark.parametrize("value", ["nan", "inf", "1e400", "-inf", "-1e400"])
def test_non_finite_twist(capsys, value):
    """A non-finite or overflowing number is refused where it is typed, naming the argument."""
    rc, _, err = cli(capsys, "ik", "tomasi-omni3", value, 0, 0)
    assert_clean_error(rc, err, "argument VX")
    rc, _, err = cli(capsys, "fk", "tomasi-omni3", 1, value, 0)
    assert_clean_error(rc, err, "argument W")


def test_negative_numbers_in_exponent_notation(capsys):
    """'-2.5e-3' is a value, not an option (argparse before Python 3.13 thinks otherwise)."""
    data = cli_json(capsys, "ik", "tomasi-omni3", "-2.5e-3", "0", "0")
    np.testing.assert_allclose(data["twist"], [-2.5e-3, 0, 0])
    data = cli_json(capsys, "fk", "tomasi-omni3", "1", "-2.5e1", "3")
    np.testing.assert_allclose(data["twist"], np.linalg.solve(hand_J("tomasi-omni3"), [1.0, -25.0, 3.0]), atol=1e-12)


def test_negative_plain_numbers(capsys):
    """Plain negative numbers are values, not options."""
    data = cli_json(capsys, "ik", "diff-drive", "-0.5", "0", "-1.5")
    np.testing.assert_allclose(data["wheel_speeds"], [(-0.5 + 0.165 * 1.5) / 0.0825, (-0.5 - 0.165 * 1.5) / 0.0825])


def test_infeasible_twist_diff_drive(capsys):
    rc, out, err = cli(capsys, "ik", "diff-drive", 0.5, 0.1, 0)
    assert out == ""
    assert_clean_error(rc, err, "--allow-infeasible", "infeasible")


def test_infeasible_twist_allowed_reports_violation(capsys):
    """With --allow-infeasible the side slip of each wheel (vy + omega x, x = 0) is reported."""
    rc, out, err = cli(capsys, "ik", "diff-drive", 0.5, 0.1, 0.2, "--allow-infeasible", "--json")
    assert rc == 0 and err == ""
    data = json.loads(out)
    assert data["feasible"] is False
    np.testing.assert_allclose(data["violation"], [0.1, 0.1], atol=1e-12)
    np.testing.assert_allclose(data["wheel_speeds"], [(0.5 - 0.165 * 0.2) / 0.0825, (0.5 + 0.165 * 0.2) / 0.0825])


def test_infeasible_text_output_says_so(capsys):
    rc, out, err = cli(capsys, "ik", "diff-drive", 0, 0.2, 0, "--allow-infeasible")
    assert rc == 0 and "infeasible" in out


def test_ackermann_beyond_steering_limit(capsys):
    """Turning on the spot needs the front wheels at 90 deg, beyond their 35 deg limit."""
    rc, _, err = cli(capsys, "ik", "ackermann", 0, 0, 1)
    assert_clean_error(rc, err, "front_", "--allow-infeasible")
    data = cli_json(capsys, "ik", "ackermann", 0, 0, 1, "--allow-infeasible")
    assert data["feasible"] is False


def test_ackermann_sideways_infeasible(capsys):
    rc, _, err = cli(capsys, "ik", "ackermann", 0, 1, 0)
    assert_clean_error(rc, err, "rear_left", "--allow-infeasible")


@pytest.mark.parametrize("name", STEERABLE_PRESETS)
def test_fk_steerable_without_steer_deg(capsys, name):
    n = len(preset_wheels(name))
    rc, _, err = cli(capsys, "fk", name, *([1.0] * n))
    assert_clean_error(rc, err, "--steer-deg")


def test_fk_steer_deg_wrong_count_and_on_unsteered(capsys):
    rc, _, err = cli(capsys, "fk", "synchro", 1, 1, 1, "--steer-deg", 0, 0)
    assert_clean_error(rc, err, "--steer-deg", "3 values")
    rc, _, err = cli(capsys, "fk", "tomasi-omni3", 1, 1, 1, "--steer-deg", 0)
    assert_clean_error(rc, err, "--steer-deg")


def test_ik_steer_hint_wrong_count(capsys):
    rc, _, err = cli(capsys, "ik", "synchro", 0.1, 0, 0, "--steer-hint-deg", 0)
    assert_clean_error(rc, err, "--steer-hint-deg")


def test_odometry_missing_log(capsys, tmp_path):
    missing = tmp_path / "missing.csv"
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", missing, "-o", tmp_path / "out.tum")
    assert_clean_error(rc, err, str(missing))
    assert not (tmp_path / "out.tum").exists()


# --- the real entry point: no traceback on bad input ----------------------------------------------------------
SUBPROCESS_ERRORS = [
    (("show", "no-such-bot"), "no-such-bot"),
    (("ik", "diff-drive", "0.5", "0.1", "0"), "--allow-infeasible"),
    (("fk", "synchro", "1", "1", "1"), "--steer-deg"),
    (("fk", "tomasi-omni3", "1", "2"), "3 wheel speeds"),
    (("odometry", "tomasi-omni3", "definitely-missing.csv", "-o", "out.tum"), "definitely-missing.csv"),
]


@pytest.mark.parametrize("argv, fragment", SUBPROCESS_ERRORS, ids=[" ".join(a[:2]) for a, _ in SUBPROCESS_ERRORS])
def test_subprocess_errors_are_one_line(tmp_path, argv, fragment):
    proc = run(*argv, cwd=tmp_path)
    assert proc.stdout == ""
    assert_clean_error(proc.returncode, proc.stderr, fragment)


def test_subprocess_usage_error_no_traceback():
    proc = run("ik", "tomasi-omni3", "zero", "0", "0")
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr and "not a number: 'zero'" in proc.stderr


def test_subprocess_ik_json_closed_form():
    proc = run("ik", "diff-drive", "0.4", "0", "1.0", "--json")
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    np.testing.assert_allclose(data["wheel_speeds"], [(0.4 - 0.165) / 0.0825, (0.4 + 0.165) / 0.0825], atol=1e-12)
