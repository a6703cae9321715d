"""``omnikin odometry`` on tick logs written the way a user writes them (CSV files).

The logs record a robot driving a known constant twist: wheel angles follow the closed
form ``angle_i(t) = row_i . twist * t`` (rows typed in from docs/conventions.md),
ticks are ``round(angle / rad_per_tick)``. The trajectory written by omnikin must
match the closed-form pose of constant-twist motion within the quantisation error
of the ticks (and to 1e-6 when the ticks are exact integers).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from support.tomasi import (
    TOMASI_F,
    TOMASI_J,
    TOMASI_RPT,
    cli,
    closed_form_pose,
    one_line_error,
    read_csv_traj,
    tomasi_file,
    wrap,
    write_log,
)


# --- closed forms --------------------------------------------------------------------------------------------
def test_closed_form_pose_is_the_textbook_circle():
    """Self-check of the helper: (v, 0, w) gives x = v/w sin(wt), y = v/w (1 - cos(wt))."""
    v, w, t = 0.3, 0.7, 2.0
    np.testing.assert_allclose(
        closed_form_pose((v, 0, w), [t])[0], [v / w * math.sin(w * t), v / w * (1 - math.cos(w * t)), w * t], atol=1e-15
    )


def quantisation_tolerance(F, rpt, twist, duration):
    """Bound on the pose error caused by rounding every tick reading to the nearest integer.

    Headings telescope: |d theta| <= 0.5 rpt |F_omega|_1 at every sample. Position: the heading
    error tilts every step (<= eps_theta * path length) and the per-sample translation error
    (<= eps_xy) enters through boundary and turning terms (<= (2 + total turn) eps_xy). Doubled.
    """
    eps_th = 0.5 * rpt * np.abs(F[2]).sum()
    eps_xy = 0.5 * rpt * max(np.abs(F[0]).sum(), np.abs(F[1]).sum()) * math.sqrt(2)
    length = math.hypot(twist[0], twist[1]) * duration
    turn = abs(twist[2]) * duration
    return 2 * (eps_th * length + (2 + turn) * eps_xy) + 1e-6, 2 * eps_th + 1e-6


# --- writing logs and running the CLI ----------------------------------------------------------------------
def tomasi_log(path, twist, dt, n):
    t = np.arange(n + 1) * dt
    angles = np.outer(t, TOMASI_J @ np.asarray(twist, float))
    ticks = np.rint(angles / TOMASI_RPT).astype(int)
    rows = [[f"{ti:.6f}", *tk] for ti, tk in zip(t, ticks.tolist(), strict=True)]
    return write_log(path, ["t", "w1", "w2", "w3"], rows), t


def read_tum(path):
    lines = path.read_text(encoding="utf-8").strip().splitlines()
    rows = [line.split() for line in lines]
    assert all(len(r) == 8 for r in rows), "TUM lines need 8 columns"
    return np.array(rows, dtype=float)


def check_tum(arr, t, expected, pos_tol, th_tol):
    np.testing.assert_allclose(arr[:, 0], t, atol=1e-9)
    np.testing.assert_array_equal(arr[:, 3:6], 0.0)  # z, qx, qy
    qz, qw = arr[:, 6], arr[:, 7]
    np.testing.assert_allclose(qz**2 + qw**2, 1.0, atol=1e-8)
    theta = 2 * np.arctan2(qz, qw)
    assert np.all(np.abs(wrap(theta - expected[:, 2])) <= th_tol)
    # qz = sin(theta/2), qw = cos(theta/2) with theta in [-pi, pi): where the expected heading is
    # clear of +-pi, the quaternion has the expected sign too
    clear = np.abs(np.abs(expected[:, 2]) - math.pi) > 10 * th_tol
    np.testing.assert_allclose(qz[clear], np.sin(expected[clear, 2] / 2), atol=th_tol)
    np.testing.assert_allclose(qw[clear], np.cos(expected[clear, 2] / 2), atol=th_tol)
    assert np.all(qw >= -1e-9)
    err = np.hypot(arr[:, 1] - expected[:, 0], arr[:, 2] - expected[:, 1])
    assert err.max() <= pos_tol, f"position error {err.max():.3g} m > {pos_tol:.3g} m"
    return err


# --- constant twists, rounded ticks ---------------------------------------------------------------------------
CASES = {
    "straight-x": ((0.3, 0.0, 0.0), 0.05, 60),
    "straight-diagonal": ((0.2, -0.15, 0.0), 0.02, 150),
    "circle": ((0.2, 0.0, 0.5), 0.25, 16),
    "circle-fine": ((0.2, 0.0, 0.5), 0.01, 400),
    "circle-clockwise": ((0.25, 0.0, -0.8), 0.1, 30),
    "sideways-arc": ((0.05, 0.2, 0.4), 0.1, 40),
    "spin": ((0.0, 0.0, 1.2), 0.05, 60),
}


@pytest.mark.parametrize("case", list(CASES))
def test_tum_matches_constant_twist(capsys, tmp_path, case):
    twist, dt, n = CASES[case]
    log, t = tomasi_log(tmp_path / "log.csv", twist, dt, n)
    out = tmp_path / "out.tum"
    rc, stdout, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", out, "--format", "tum")
    assert rc == 0, err
    assert out.name in stdout
    arr = read_tum(out)
    assert arr.shape == (n + 1, 8)
    pos_tol, th_tol = quantisation_tolerance(TOMASI_F, TOMASI_RPT, twist, t[-1])
    check_tum(arr, t, closed_form_pose(twist, t), pos_tol, th_tol)


def test_tum_circle_final_pose_textbook(capsys, tmp_path):
    """The brief's circle: x = v/w sin(wt), y = v/w (1 - cos(wt)) at the last sample."""
    v, w, dt, n = 0.2, 0.5, 0.2, 20
    log, t = tomasi_log(tmp_path / "log.csv", (v, 0.0, w), dt, n)
    out = tmp_path / "out.tum"
    assert cli(capsys, "odometry", "tomasi-omni3", log, "-o", out, "--format", "tum")[0] == 0
    last = read_tum(out)[-1]
    T = t[-1]
    pos_tol, th_tol = quantisation_tolerance(TOMASI_F, TOMASI_RPT, (v, 0, w), T)
    assert last[1] == pytest.approx(v / w * math.sin(w * T), abs=pos_tol)
    assert last[2] == pytest.approx(v / w * (1 - math.cos(w * T)), abs=pos_tol)
    assert last[6] == pytest.approx(math.sin(w * T / 2), abs=th_tol)
    assert last[7] == pytest.approx(math.cos(w * T / 2), abs=th_tol)


def test_euler_is_worse_than_exact_on_coarse_samples(capsys, tmp_path):
    """The tolerance above is tight enough to see first-order integration error."""
    twist, dt, n = (0.2, 0.0, 0.5), 0.25, 16
    log, t = tomasi_log(tmp_path / "log.csv", twist, dt, n)
    exact, euler = tmp_path / "exact.csv", tmp_path / "euler.csv"
    assert cli(capsys, "odometry", "tomasi-omni3", log, "-o", exact)[0] == 0
    assert cli(capsys, "odometry", "tomasi-omni3", log, "-o", euler, "--method", "euler")[0] == 0
    expected = closed_form_pose(twist, t)[-1]
    pos_tol, _ = quantisation_tolerance(TOMASI_F, TOMASI_RPT, twist, t[-1])
    err_exact = np.hypot(*(read_csv_traj(exact)[-1, 1:3] - expected[:2]))
    err_euler = np.hypot(*(read_csv_traj(euler)[-1, 1:3] - expected[:2]))
    assert err_exact <= pos_tol < err_euler


@pytest.mark.parametrize("case", ["straight-diagonal", "circle", "sideways-arc"])
def test_csv_format_matches_constant_twist(capsys, tmp_path, case):
    twist, dt, n = CASES[case]
    log, t = tomasi_log(tmp_path / "log.csv", twist, dt, n)
    out = tmp_path / "out.csv"
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", out, "--format", "csv")
    assert rc == 0, err
    arr = read_csv_traj(out)
    assert arr.shape == (n + 1, 4)
    expected = closed_form_pose(twist, t)
    pos_tol, th_tol = quantisation_tolerance(TOMASI_F, TOMASI_RPT, twist, t[-1])
    np.testing.assert_allclose(arr[:, 0], t, atol=1e-9)
    assert np.all(np.abs(wrap(arr[:, 3] - expected[:, 2])) <= th_tol)
    assert np.all(np.hypot(arr[:, 1] - expected[:, 0], arr[:, 2] - expected[:, 1]) <= pos_tol)
    assert np.all((arr[:, 3] >= -math.pi) & (arr[:, 3] < math.pi))


def test_default_format_is_csv(capsys, tmp_path):
    log, _ = tomasi_log(tmp_path / "log.csv", (0.1, 0, 0), 0.1, 5)
    out = tmp_path / "out.txt"
    assert cli(capsys, "odometry", "tomasi-omni3", log, "-o", out)[0] == 0
    assert out.read_text(encoding="utf-8").startswith("t,x,y,theta")


def test_json_summary(capsys, tmp_path):
    twist, dt, n = (0.3, 0.0, 0.0), 0.05, 60
    log, t = tomasi_log(tmp_path / "log.csv", twist, dt, n)
    rc, out, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", tmp_path / "o.tum", "--format", "tum", "--json")
    assert rc == 0, err
    data = json.loads(out)
    assert data["samples"] == n + 1 and data["duration"] == pytest.approx(t[-1])
    pos_tol, _ = quantisation_tolerance(TOMASI_F, TOMASI_RPT, twist, t[-1])
    assert data["final_pose"][0] == pytest.approx(0.3 * t[-1], abs=pos_tol)
    assert data["path_length"] == pytest.approx(0.3 * t[-1], abs=2 * pos_tol)
    assert data["format"] == "tum"


# --- exact integer ticks: no quantisation at all ---------------------------------------------------------------
def exact_tick_log(path, per_sample, dt, n, header=("t", "w1", "w2", "w3"), transform=None):
    ticks = np.outer(np.arange(n + 1), per_sample).astype(np.int64)
    if transform is not None:
        ticks = transform(ticks)
    t = np.arange(n + 1) * dt
    rows = [[f"{ti:.6f}", *tk] for ti, tk in zip(t, ticks.tolist(), strict=True)]
    return write_log(path, header, rows), t


@pytest.mark.parametrize("per_sample", [(300, 200, 250), (40, -10, 25), (-120, 60, 7)])
@pytest.mark.parametrize("fmt", ["tum", "csv"])
def test_exact_ticks_give_exact_pose(capsys, tmp_path, per_sample, fmt):
    """Integer ticks per sample = the twist F n rpt / dt exactly: the exact SE(2) integration
    reproduces the closed form to the printed precision (a midpoint or Euler rule would not:
    the first case turns ~0.96 rad per sample)."""
    dt, n = 0.5, 20
    twist = TOMASI_F @ (np.array(per_sample) * TOMASI_RPT) / dt
    log, t = exact_tick_log(tmp_path / "log.csv", per_sample, dt, n)
    out = tmp_path / f"out.{fmt}"
    assert cli(capsys, "odometry", "tomasi-omni3", log, "-o", out, "--format", fmt)[0] == 0
    expected = closed_form_pose(twist, t)
    if fmt == "tum":
        check_tum(read_tum(out), t, expected, 1e-6, 1e-7)
    else:
        arr = read_csv_traj(out)
        np.testing.assert_allclose(arr[:, 1:3], expected[:, :2], atol=1e-6)
        assert np.all(np.abs(wrap(arr[:, 3] - expected[:, 2])) < 1e-7)


@pytest.mark.parametrize("representation", ["unsigned", "signed"])
def test_counter_wrap_16_bit(capsys, tmp_path, representation):
    """A 16-bit counter wraps past 65535; with --counter-bits 16 the pose is the closed form;
    without any counter width the wrap is a jump no wheel can make: refused, pointing at the width."""
    per_sample, dt, n = (3000, -2000, 1000), 0.1, 30
    if representation == "unsigned":
        transform = lambda k: k % 65536  # noqa: E731
    else:
        transform = lambda k: (k + 32768) % 65536 - 32768  # noqa: E731
    log, t = exact_tick_log(tmp_path / "log.csv", per_sample, dt, n, transform=transform)
    raw = np.loadtxt(log, delimiter=",", skiprows=1)
    assert np.any(np.abs(np.diff(raw[:, 1:], axis=0)) > 30000), "the log must actually wrap"
    twist = TOMASI_F @ (np.array(per_sample) * TOMASI_RPT) / dt
    out = tmp_path / "out.tum"
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", out, "--format", "tum", "--counter-bits", 16)
    assert rc == 0, err
    check_tum(read_tum(out), t, closed_form_pose(twist, t), 1e-6, 1e-7)
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", tmp_path / "other.tum", "--format", "tum")
    line = one_line_error(rc, err)
    assert "--counter-bits" in line and "encoder.counter_bits" in line and "impossible jump" in line
    first_wrap = 1 + int(np.argmax(np.any(np.abs(np.diff(raw[:, 1:], axis=0)) > 30000, axis=1)))
    assert f"line {first_wrap + 2}:" in line  # header is line 1, sample k is line k + 2
    assert not (tmp_path / "other.tum").exists()


def test_user_log_conventions(capsys, tmp_path):
    """t first, wheel columns in any order, spaces after commas, comment and blank lines, CRLF ends."""
    per_sample, dt, n = (40, -10, 25), 0.5, 6
    twist = TOMASI_F @ (np.array(per_sample) * TOMASI_RPT) / dt
    lines = ["# recorded on the bench", "t, w3, w1, w2", ""]
    for k in range(n + 1):
        lines.append(f"{k * dt:.3f}, {k * per_sample[2]}, {k * per_sample[0]}, {k * per_sample[1]}")
        if k == 2:
            lines.append("# a comment in the middle")
    log = tmp_path / "log.csv"
    log.write_bytes(("\r\n".join(lines) + "\r\n").encode())
    out = tmp_path / "out.tum"
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", out, "--format", "tum")
    assert rc == 0, err
    t = np.arange(n + 1) * dt
    check_tum(read_tum(out), t, closed_form_pose(twist, t), 1e-6, 1e-7)


# --- other robots ------------------------------------------------------------------------------------------------
def test_diff_drive_circle_with_gearbox(capsys, tmp_path):
    """diff-drive: 500 ticks/rev through a 19.7:1 gearbox; left = (v - 0.165 w)/r, right = (v + 0.165 w)/r."""
    r, half, rpt = 0.0825, 0.165, 2 * math.pi / (500 * 19.7)
    v, w, dt, n = 0.3, 0.6, 0.1, 50
    t = np.arange(n + 1) * dt
    left = np.rint((v - half * w) / r * t / rpt).astype(int)
    right = np.rint((v + half * w) / r * t / rpt).astype(int)
    log = write_log(
        tmp_path / "dd.csv",
        ["t", "left", "right"],
        [[f"{a:.3f}", b, c] for a, b, c in zip(t, left.tolist(), right.tolist(), strict=True)],
    )
    out = tmp_path / "dd.tum"
    rc, _, err = cli(capsys, "odometry", "diff-drive", log, "-o", out, "--format", "tum")
    assert rc == 0, err
    F = np.array([[r / 2, r / 2], [0, 0], [-r / (2 * half), r / (2 * half)]])
    pos_tol, th_tol = quantisation_tolerance(F, rpt, (v, 0, w), t[-1])
    check_tum(read_tum(out), t, closed_form_pose((v, 0, w), t), pos_tol, th_tol)


def test_diff_drive_castor_column_is_unknown(capsys, tmp_path):
    """The castor has no encoder, so it has no column."""
    log = write_log(tmp_path / "dd.csv", ["t", "left", "right", "castor"], [[0, 0, 0, 0], [0.1, 5, 5, 5]])
    rc, _, err = cli(capsys, "odometry", "diff-drive", log, "-o", tmp_path / "o.csv")
    assert rc == 2 and "castor" in err and "unknown" in err


@pytest.mark.parametrize("steer_deg", [30.0, -100.0])
def test_synchro_parallel_steering(capsys, tmp_path, steer_deg):
    """All wheels steered to phi rolling equally: straight line along phi at v = n rpt r / dt."""
    rpt, r, n_per, dt, n = 2 * math.pi / 1024, 0.05, 50, 0.1, 20
    v = n_per * rpt * r / dt
    phi = math.radians(steer_deg)
    t = np.arange(n + 1) * dt
    header = ["t", "w2_steer_deg", "w1", "w2", "w3", "w1_steer_deg", "w3_steer_deg"]
    rows = [[f"{ti:.3f}", steer_deg, k * n_per, k * n_per, k * n_per, steer_deg, steer_deg] for k, ti in enumerate(t)]
    log = write_log(tmp_path / "sync.csv", header, rows)
    out = tmp_path / "sync.tum"
    rc, _, err = cli(capsys, "odometry", "synchro", log, "-o", out, "--format", "tum")
    assert rc == 0, err
    check_tum(read_tum(out), t, closed_form_pose((v * math.cos(phi), v * math.sin(phi), 0.0), t), 1e-6, 1e-7)


def test_synchro_spin_in_place(capsys, tmp_path):
    """Wheels steered tangentially (delta = beta + 90 deg) and rolling equally: rotation about the origin."""
    rpt, r, dist, n_per, dt, n = 2 * math.pi / 1024, 0.05, 0.2, 40, 0.1, 25
    w = n_per * rpt * r / dist / dt
    steer = [90.0, -150.0, -30.0]  # beta + 90 for beta = 0, 120, 240, wrapped
    t = np.arange(n + 1) * dt
    header = ["t", "w1", "w2", "w3", "w1_steer_deg", "w2_steer_deg", "w3_steer_deg"]
    rows = [[f"{ti:.3f}", k * n_per, k * n_per, k * n_per, *steer] for k, ti in enumerate(t)]
    log = write_log(tmp_path / "spin.csv", header, rows)
    out = tmp_path / "spin.tum"
    rc, _, err = cli(capsys, "odometry", "synchro", log, "-o", out, "--format", "tum")
    assert rc == 0, err
    check_tum(read_tum(out), t, closed_form_pose((0.0, 0.0, w), t), 1e-6, 1e-7)


def test_synchro_without_steer_columns(capsys, tmp_path):
    log = write_log(tmp_path / "sync.csv", ["t", "w1", "w2", "w3"], [[0, 0, 0, 0], [0.1, 5, 5, 5], [0.2, 9, 9, 9]])
    rc, _, err = cli(capsys, "odometry", "synchro", log, "-o", tmp_path / "o.tum")
    line = one_line_error(rc, err)
    for col in ("w1_steer_deg", "w2_steer_deg", "w3_steer_deg"):
        assert col in line
    assert "missing" in line and str(log) in line


def test_synchro_nan_steering_cell(capsys, tmp_path):
    header = ["t", "w1", "w2", "w3", "w1_steer_deg", "w2_steer_deg", "w3_steer_deg"]
    log = write_log(tmp_path / "sync.csv", header, [[0, 0, 0, 0, 0, 0, 0], [0.1, 5, 5, 5, 0, "nan", 0]])
    rc, _, err = cli(capsys, "odometry", "synchro", log, "-o", tmp_path / "o.tum")
    line = one_line_error(rc, err)
    assert "line 3" in line and "'w2_steer_deg'" in line


def test_max_speed_jump_detected(capsys, tmp_path):
    """With max_speed in the robot file a reading that would need a far faster wheel is refused."""
    robot = tomasi_file(tmp_path, wheel_extra=", max_speed: 30.0", name="fast.yaml")
    # 30 rad/s for 0.01 s is ~29 ticks; 5000 ticks is impossible
    log = write_log(
        tmp_path / "log.csv",
        ["t", "w1", "w2", "w3"],
        [[0.0, 0, 0, 0], [0.01, 10, 10, 10], [0.02, 20, 5000, 20], [0.03, 30, 5010, 30]],
    )
    rc, _, err = cli(capsys, "odometry", robot, log, "-o", tmp_path / "o.tum")
    line = one_line_error(rc, err)
    assert "jump" in line and "'w2'" in line and ("sample 2" in line or "line 4" in line)


# --- broken logs ---------------------------------------------------------------------------------------------------
GOOD = [[0.0, 0, 0, 0], [0.1, 5, -3, 2], [0.2, 10, -6, 4], [0.3, 15, -9, 6]]
H = ["t", "w1", "w2", "w3"]


def rows_with(line_no, row):
    """GOOD rows with the data row on file line ``line_no`` (header = line 1) replaced."""
    rows = [list(r) for r in GOOD]
    rows[line_no - 2] = row
    return rows


BROKEN = [
    # id, header, rows, required fragments, alternatives (at least one must appear)
    ("missing-wheel-column", ["t", "w1", "w2"], [r[:3] for r in GOOD], ["w3", "missing", "line 1"], []),
    ("unknown-column", H + ["battery"], [r + [12.1] for r in GOOD], ["battery", "unknown"], []),
    ("duplicate-column", H + ["w2"], [r + [0] for r in GOOD], ["duplicate", "w2"], []),
    ("first-column-not-t", ["time", "w1", "w2", "w3"], GOOD, ["'t'"], []),
    ("non-numeric-cell", H, rows_with(4, [0.2, 10, "ten", 4]), ["line 4", "'w2'", "ten"], []),
    ("empty-cell", H, rows_with(3, [0.1, 5, -3, ""]), ["line 3", "'w3'"], []),
    ("nan-cell", H, rows_with(3, [0.1, "nan", -3, 2]), ["line 3", "'w1'"], []),
    ("inf-cell", H, rows_with(3, [0.1, 5, "inf", 2]), ["line 3", "'w2'"], []),
    ("nan-time", H, rows_with(4, ["NaN", 10, -6, 4]), ["line 4", "'t'"], []),
    ("too-few-fields", H, rows_with(3, [0.1, 5, -3]), ["line 3", "fields"], []),
    ("too-many-fields", H, rows_with(4, [0.2, 10, -6, 4, 99]), ["line 4", "fields"], []),
    ("time-goes-back", H, rows_with(4, [0.05, 10, -6, 4]), ["timestamp"], ["sample 2", "line 4"]),
    ("time-repeated", H, rows_with(5, [0.2, 15, -9, 6]), ["timestamp"], ["sample 3", "line 5"]),
    ("reading-above-16-bit", H, rows_with(4, [0.2, 70000, -6, 4]), ["16-bit", "'w1'"], ["sample 2", "line 4"]),
    ("reading-below-16-bit", H, rows_with(3, [0.1, 5, -40000, 2]), ["16-bit", "'w2'"], ["sample 1", "line 3"]),
]


@pytest.mark.parametrize("header, rows, fragments, alternatives", [c[1:] for c in BROKEN], ids=[c[0] for c in BROKEN])
def test_broken_log(capsys, tmp_path, header, rows, fragments, alternatives):
    log = write_log(tmp_path / "broken.csv", header, rows)
    out = tmp_path / "out.tum"
    rc, stdout, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", out, "--format", "tum", "--counter-bits", 16)
    line = one_line_error(rc, err)
    assert stdout == ""
    for frag in fragments:
        assert frag in line, (frag, line)
    if alternatives:
        assert any(a in line for a in alternatives), (alternatives, line)
    assert not out.exists()


@pytest.mark.parametrize(
    "content, fragment",
    [
        ("", "empty"),
        ("\n\n", "empty"),
        ("# only a comment\n", "empty"),
        ("t,w1,w2,w3\n", "sample"),
        ("t,w1,w2,w3\n0.0,0,0,0\n", "sample"),
    ],
    ids=["empty", "blank-lines", "comment-only", "header-only", "one-sample"],
)
def test_too_short_logs(capsys, tmp_path, content, fragment):
    log = tmp_path / "short.csv"
    log.write_text(content, encoding="utf-8")
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", tmp_path / "o.tum")
    line = one_line_error(rc, err)
    assert fragment in line and str(log) in line


def test_repeated_timestamp_without_counter_bits(capsys, tmp_path):
    log = write_log(tmp_path / "rep.csv", H, rows_with(3, [0.0, 5, -3, 2]))
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", tmp_path / "o.tum")
    line = one_line_error(rc, err)
    assert "sample 1" in line or "line 3" in line


def test_exact_duplicate_rows_are_skipped_with_a_warning(capsys, tmp_path):
    """A logger writing the same sample twice: the row is dropped, the CLI says which line."""
    per_sample, dt, n = (40, -10, 25), 0.5, 4
    twist = TOMASI_F @ (np.array(per_sample) * TOMASI_RPT) / dt
    log, t = exact_tick_log(tmp_path / "log.csv", per_sample, dt, n)
    lines = log.read_text(encoding="utf-8").splitlines()
    lines.insert(3, lines[2])  # line 4 repeats line 3
    log.write_text("\n".join(lines) + "\n", encoding="utf-8")
    out = tmp_path / "out.tum"
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", out, "--format", "tum")
    assert rc == 0
    assert "warning" in err and "skipped 1 row" in err and "line 4" in err
    check_tum(read_tum(out), t, closed_form_pose(twist, t), 1e-6, 1e-7)


def test_invalid_counter_bits(capsys, tmp_path):
    log = write_log(tmp_path / "ok.csv", H, GOOD)
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", tmp_path / "o.tum", "--counter-bits", 1)
    assert "counter_bits" in one_line_error(rc, err)


def test_log_is_a_directory(capsys, tmp_path):
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", tmp_path, "-o", tmp_path / "o.tum")
    assert str(tmp_path) in one_line_error(rc, err)


def test_output_not_writable(capsys, tmp_path):
    log = write_log(tmp_path / "ok.csv", H, GOOD)
    target = tmp_path / "no" / "dir" / "o.tum"
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", target, "--format", "tum")
    line = one_line_error(rc, err)
    assert str(target) in line and "does not exist" in line


def test_log_not_utf8(capsys, tmp_path):
    """A Latin-1 byte in the log: one-line error naming the file, no UnicodeDecodeError traceback."""
    log = tmp_path / "latin1.csv"
    log.write_bytes(b"t,w1,w2,w3\n0,0,0,0\n0.1,5,5,5\n# caf\xe9\n")
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", tmp_path / "o.tum")
    assert str(log) in one_line_error(rc, err)


def test_log_with_utf8_bom(capsys, tmp_path):
    per_sample, dt, n = (40, -10, 25), 0.5, 4
    twist = TOMASI_F @ (np.array(per_sample) * TOMASI_RPT) / dt
    log, t = exact_tick_log(tmp_path / "log.csv", per_sample, dt, n)
    log.write_bytes(b"\xef\xbb\xbf" + log.read_bytes())
    out = tmp_path / "out.tum"
    rc, _, err = cli(capsys, "odometry", "tomasi-omni3", log, "-o", out, "--format", "tum")
    assert rc == 0, err
    check_tum(read_tum(out), t, closed_form_pose(twist, t), 1e-6, 1e-7)


# --- the real entry point --------------------------------------------------------------------------------------------
def test_subprocess_odometry_tum(tmp_path):
    twist, dt, n = (0.2, 0.0, 0.5), 0.1, 40
    log, t = tomasi_log(tmp_path / "log.csv", twist, dt, n)
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "omnikin.cli.main",
            "odometry",
            "tomasi-omni3",
            "log.csv",
            "-o",
            "out.tum",
            "--format",
            "tum",
        ],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    pos_tol, th_tol = quantisation_tolerance(TOMASI_F, TOMASI_RPT, twist, t[-1])
    check_tum(read_tum(tmp_path / "out.tum"), t, closed_form_pose(twist, t), pos_tol, th_tol)


def test_subprocess_broken_log_no_traceback(tmp_path):
    write_log(tmp_path / "bad.csv", H, rows_with(4, [0.2, 10, "x", 4]))
    proc = subprocess.run(
        [sys.executable, "-m", "omnikin.cli.main", "odometry", "tomasi-omni3", "bad.csv", "-o", "out.tum"],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=tmp_path,
    )
    line = one_line_error(proc.returncode, proc.stderr)
    assert "line 4" in line and "'w2'" in line
