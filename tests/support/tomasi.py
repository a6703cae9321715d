"""Closed forms and small helpers shared by the odometry tests (tomasi-omni3 typed in from its
robot file and docs/conventions.md, never taken from omnikin), and the CLI runner."""

from __future__ import annotations

import math

import numpy as np

from support.cli import run_cli as cli  # noqa: F401  (re-exported for the odometry tests)

TOMASI_L, TOMASI_R = 0.113, 0.04125
TOMASI_RPT = 2 * math.pi / 600  # rad per tick (600 ticks/rev, no gearbox)
TOMASI_BETAS = np.radians([0.0, 120.0, 240.0])
TOMASI_J = np.array([[-math.sin(b), math.cos(b), TOMASI_L] for b in TOMASI_BETAS]) / TOMASI_R
TOMASI_F = np.linalg.inv(TOMASI_J)


def wrap(a):
    return (np.asarray(a) + math.pi) % (2 * math.pi) - math.pi


def closed_form_pose(twist, t):
    """Pose (x, y, theta) after constant body twist for times t, from the origin (theta wrapped)."""
    vx, vy, w = twist
    t = np.asarray(t, dtype=float)
    if w == 0:
        return np.stack([vx * t, vy * t, np.zeros_like(t)], axis=-1)
    th = w * t
    x = (vx * np.sin(th) - vy * (1 - np.cos(th))) / w
    y = (vx * (1 - np.cos(th)) + vy * np.sin(th)) / w
    return np.stack([x, y, wrap(th)], axis=-1)


def se2_step(pose, inc):
    """Pose after the body increment ``inc = (a, b, phi)`` at constant twist (SE(2) exponential)."""
    x, y, th = pose
    a, b, phi = inc
    if abs(phi) < 1e-12:
        k, h = 1.0, th
    else:
        k, h = math.sin(phi / 2) / (phi / 2), th + phi / 2
    th2 = th + phi
    th2 = th2 - 2 * math.pi * math.floor((th2 + math.pi) / (2 * math.pi))
    return (x + k * (math.cos(h) * a - math.sin(h) * b), y + k * (math.sin(h) * a + math.cos(h) * b), th2)


def tomasi_poses(tick_increments):
    """Closed-form poses from the origin for a list of per-interval tick increments (3 wheels)."""
    poses = [(0.0, 0.0, 0.0)]
    for d in tick_increments:
        poses.append(se2_step(poses[-1], TOMASI_F @ (np.asarray(d, float) * TOMASI_RPT)))
    return np.array(poses)


def assert_poses_close(actual, expected, atol=1e-12):
    actual, expected = np.asarray(actual, float), np.asarray(expected, float)
    assert actual.shape == expected.shape
    d = actual - expected
    d[..., 2] = (d[..., 2] + math.pi) % (2 * math.pi) - math.pi
    assert np.max(np.abs(d)) <= atol, (actual, expected)


def write_log(path, header, rows):
    with open(path, "w", encoding="utf-8", newline="") as f:
        f.write(",".join(header) + "\n")
        for row in rows:
            f.write(",".join(str(v) for v in row) + "\n")
    return path


def read_csv_traj(path):
    lines = path.read_text(encoding="utf-8").strip().splitlines()
    assert lines[0].replace(" ", "") == "t,x,y,theta"
    rows = [line.split(",") for line in lines[1:]]
    assert all(len(r) == 4 for r in rows)
    return np.array(rows, dtype=float)


def one_line_error(rc, err):
    assert rc == 2, err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("omnikin: error: "), err
    return lines[0]


def tomasi_file(tmp_path, encoder_extra="", wheel_extra="", name="r.yaml"):
    """tomasi-omni3 written out as a robot file, with extra encoder / wheel fields."""
    p = tmp_path / name
    p.write_text(
        "omnikin: 1\nname: tomasi-file\nwheels:\n"
        + "".join(
            f"  - {{name: w{i + 1}, type: omni, distance: 0.113, angle_deg: {b}, radius: 0.04125{wheel_extra}, "
            f"encoder: {{ticks_per_rev: 600{encoder_extra}}}}}\n"
            for i, b in enumerate((0, 120, 240))
        ),
        encoding="utf-8",
    )
    return p
