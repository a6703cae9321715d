"""Trajectory metrics (omnikin.evaluation.metrics) and trajectory files (omnikin.io.trajectories).

Hand-computed cases: a rigidly moved copy has ATE 0 after alignment and the motion's
displacement without; a constant drift gives a constant, closed-form RPE. When ``evo`` is
installed (GPL; a test-time comparison only, never a dependency) the numbers must equal
evo's on the same TUM files within 1e-9.
"""

from __future__ import annotations

import argparse
import copy
import json
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from omnikin.errors import MetricsInputError, OmnikinError, TrajectoryFileError
from omnikin.evaluation import metrics as m
from omnikin.io.trajectories import read_trajectory, write_trajectory


def wrap(a):
    return (np.asarray(a) + math.pi) % (2 * math.pi) - math.pi


def se2(x, y, th):
    return np.array([x, y, th], dtype=float)


def rigid(poses, x, y, th):
    """Poses moved by the rigid motion (x, y, th), typed in: R(th) p + (x, y), heading + th."""
    c, s = math.cos(th), math.sin(th)
    p = np.asarray(poses, dtype=float)
    return np.column_stack([c * p[:, 0] - s * p[:, 1] + x, s * p[:, 0] + c * p[:, 1] + y, wrap(p[:, 2] + th)])


def wiggly(n=200, seed=0):
    """A smooth trajectory that turns both ways (not collinear)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 0.1
    th = 0.8 * np.sin(0.3 * t) + 0.2 * t
    x = np.cumsum(0.1 * np.cos(th))
    y = np.cumsum(0.1 * np.sin(th))
    return t, np.column_stack([x, y, wrap(th)]) + rng.normal(0, 1e-9, (n, 3))


# --- statistics -----------------------------------------------------------------------------------------
def test_statistics_by_hand():
    s = m.statistics([3.0, 4.0])
    assert s.rmse == pytest.approx(math.sqrt(12.5), abs=1e-15)
    assert (s.mean, s.median, s.std, s.min, s.max, s.sse, s.count) == (3.5, 3.5, 0.5, 3.0, 4.0, 25.0, 2)
    s = m.statistics([1.0, 2.0, 6.0])
    assert s.median == 2.0 and s.std == pytest.approx(math.sqrt(((1 - 3) ** 2 + 1 + 9) / 3), abs=1e-15)


@pytest.mark.parametrize("bad", [[], [[1.0]], [1.0, math.nan]])
def test_statistics_refuses(bad):
    with pytest.raises(MetricsInputError):
        m.statistics(bad)


# --- ATE ------------------------------------------------------------------------------------------------
def test_translated_copy_ate_is_offset_without_alignment_and_zero_with():
    t, ref = wiggly()
    est = rigid(ref, 0.3, -0.4, 0.0)
    a = m.ate(t, ref, t, est)
    np.testing.assert_allclose(a.errors, 0.5, atol=1e-12)
    assert a.stats.rmse == pytest.approx(0.5, abs=1e-12) and a.stats.std < 1e-12 and a.alignment is None
    b = m.ate(t, ref, t, est, align=True)
    assert b.stats.max < 1e-12
    np.testing.assert_allclose(b.alignment.pose, [-0.3, 0.4, 0.0], atol=1e-12)


def test_rotated_copy_ate():
    """Rotated by phi about the origin: each point is off by the chord 2 |p| sin(phi/2)."""
    t, ref = wiggly()
    phi = 0.7
    est = rigid(ref, 0.0, 0.0, phi)
    a = m.ate(t, ref, t, est)
    np.testing.assert_allclose(a.errors, 2 * np.hypot(ref[:, 0], ref[:, 1]) * math.sin(phi / 2), atol=1e-12)
    b = m.ate(t, ref, t, est, align=True)
    assert b.stats.max < 1e-12
    assert b.alignment.theta == pytest.approx(-phi, abs=1e-12)
    np.testing.assert_allclose(b.alignment.apply(est), ref, atol=1e-12)


@given(st.floats(-5, 5), st.floats(-5, 5), st.floats(-3.1, 3.1))
def test_any_rigid_motion_aligns_to_zero(x, y, th):
    t, ref = wiggly(60, seed=3)
    a = m.ate(t, ref, t, rigid(ref, x, y, th), align=True)
    assert a.stats.max < 1e-9


def test_alignment_is_the_least_squares_optimum():
    """Perturbing the closed-form alignment in any direction can only raise the squared error sum."""
    rng = np.random.default_rng(5)
    _, ref = wiggly(80)
    est = rigid(ref, 1.0, 2.0, -0.4) + np.column_stack([rng.normal(0, 0.05, (80, 2)), np.zeros(80)])
    al = m.align_se2(ref[:, :2], est[:, :2])

    def sse(p):
        moved = rigid(est, *p)
        return np.sum((moved[:, :2] - ref[:, :2]) ** 2)

    best = sse(al.pose)
    for d in np.eye(3) * 1e-4:
        assert sse(al.pose + d) > best and sse(al.pose - d) > best


def test_alignment_of_collinear_positions_is_defined():
    t = np.arange(10.0)
    ref = np.column_stack([t, np.zeros(10), np.zeros(10)])
    est = rigid(ref, 1.0, -1.0, 0.5)
    assert m.ate(t, ref, t, est, align=True).stats.max < 1e-12


def test_alignment_refuses_degenerate_input():
    t = np.arange(5.0)
    ref = np.column_stack([t, t, np.zeros(5)])
    est = np.zeros((5, 3))
    with pytest.raises(MetricsInputError, match="alignment is undefined"):
        m.ate(t, ref, t, est, align=True)
    with pytest.raises(MetricsInputError, match="alignment is undefined"):
        m.ate(t[:1], ref[:1], t[:1], est[:1], align=True)


# --- RPE ------------------------------------------------------------------------------------------------
def test_rpe_of_constant_drift_is_closed_form():
    """Reference straight along x at 1 m per frame; estimate turning w per frame (constant twist).

    Over d frames: Q_rel = (d, 0, 0), P_rel = exp(d (1, 0, w)) = (sin(dw)/w, (1 - cos(dw))/w, dw),
    E = Q_rel^-1 P_rel = (sin(dw)/w - d, (1 - cos(dw))/w, dw).
    """
    w, n = 0.01, 101
    k = np.arange(n, dtype=float)
    ref = np.column_stack([k, np.zeros(n), np.zeros(n)])
    est = np.column_stack([np.sin(k * w) / w, (1 - np.cos(k * w)) / w, wrap(k * w)])
    for d in (1, 4, 10):
        r = m.rpe(k, ref, k, est, delta=d)
        trans = math.hypot(math.sin(d * w) / w - d, (1 - math.cos(d * w)) / w)
        assert len(r.translation) == (n - 1) // d
        np.testing.assert_allclose(r.translation, trans, rtol=1e-9)
        np.testing.assert_allclose(r.rotation, d * w, rtol=1e-9)
        assert r.translation_stats.rmse == pytest.approx(trans, rel=1e-9)
        deg = m.rpe(k, ref, k, est, delta=d, angle_unit="deg")
        np.testing.assert_allclose(deg.rotation, math.degrees(d * w), rtol=1e-9)
    # ATE grows, RPE does not
    assert m.ate(k, ref, k, est).errors[-1] > 10 * trans


def test_rpe_scale_drift():
    """Estimate 1 % too long per frame on a straight line: translation RPE 0.01 d, rotation 0."""
    k = np.arange(50, dtype=float)
    ref = np.column_stack([k, np.zeros(50), np.zeros(50)])
    est = ref * [1.01, 1, 1]
    r = m.rpe(k, ref, k, est, delta=3, all_pairs=True)
    assert len(r.translation) == 47
    np.testing.assert_allclose(r.translation, 0.03, rtol=1e-12)
    assert r.rotation_stats.max == 0.0


def test_rpe_pairs():
    np.testing.assert_array_equal(m.index_pairs(7, 3), [[0, 3], [3, 6]])
    np.testing.assert_array_equal(m.index_pairs(7, 3, all_pairs=True), [[0, 3], [1, 4], [2, 5], [3, 6]])
    np.testing.assert_array_equal(m.index_pairs(6, 3), [[0, 3]])


def test_rpe_half_turn_is_pi():
    t = np.arange(2.0)
    ref = np.zeros((2, 3))
    est = np.array([[0, 0, 0], [0, 0, math.pi]])
    assert m.rpe(t, ref, t, est).rotation[0] == pytest.approx(math.pi, abs=1e-15)


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"delta": 0}, "delta"),
        ({"delta": 1.5}, "delta"),
        ({"delta": 10}, "more than 10"),
        ({"angle_unit": "grad"}, "angle_unit"),
    ],
)
def test_rpe_refuses(kw, match):
    t = np.arange(10.0)
    p = np.zeros((10, 3))
    with pytest.raises(MetricsInputError, match=match):
        m.rpe(t, p, t, p, **kw)


# --- association ------------------------------------------------------------------------------------------
def test_association_nearest_within_max_diff():
    ref = np.array([0.0, 1.0, 2.0, 3.0])
    est = np.array([0.004, 1.02, 1.995, 5.0])
    i_ref, i_est = m.associate(ref, est, max_diff=0.01)
    np.testing.assert_array_equal(i_ref, [0, 2])
    np.testing.assert_array_equal(i_est, [0, 2])
    i_ref, i_est = m.associate(ref, est, max_diff=0.05)
    np.testing.assert_array_equal(i_ref, [0, 1, 2])


def test_association_walks_the_shorter_and_may_reuse():
    ref = np.array([0.0, 1.0])
    est = np.array([0.0, 0.001, 0.002, 0.999])
    i_ref, i_est = m.associate(ref, est, max_diff=0.01)  # est longer: each ref pose once
    np.testing.assert_array_equal(i_ref, [0, 1])
    np.testing.assert_array_equal(i_est, [0, 3])
    i_ref, i_est = m.associate(est, ref, max_diff=0.01)  # now ref (est above) is longer: est walks
    np.testing.assert_array_equal(i_ref, [0, 3])


def test_association_ties_go_to_the_earlier_and_offset_applies():
    ref = np.array([0.0, 0.5, 1.0, 1.5])
    est = np.array([0.25, 1.25])
    i_ref, _ = m.associate(ref, est, max_diff=0.3)
    np.testing.assert_array_equal(i_ref, [0, 2])
    i_ref, _ = m.associate(ref, est, max_diff=0.01, offset=0.25)  # est + 0.25 = 0.5, 1.5
    np.testing.assert_array_equal(i_ref, [1, 3])


def test_association_without_match_says_so():
    with pytest.raises(MetricsInputError, match="no matching timestamps"):
        m.associate([0.0, 1.0], [5.0, 6.0])


@pytest.mark.parametrize(
    "t, poses, match",
    [
        ([], np.zeros((0, 3)), "empty"),
        ([0.0, 1.0], np.zeros((3, 3)), "2 timestamps but 3 poses"),
        ([0.0, 1.0], np.zeros((2, 2)), r"shape \(N, 3\)"),
        ([0.0, math.nan], np.zeros((2, 3)), "non-finite timestamp"),
        ([0.0, 1.0], [[0, 0, 0], [0, math.nan, 0]], "non-finite y .* at pose 1"),
        ([0.0, 1.0, 1.0], np.zeros((3, 3)), "increase strictly; pose 2"),
    ],
)
def test_bad_trajectories_are_named(t, poses, match):
    good_t, good = np.arange(3.0), np.zeros((3, 3))
    with pytest.raises(MetricsInputError, match="estimate: .*" + match):
        m.ate(good_t, good, t, poses)
    with pytest.raises(OmnikinError, match="reference: .*" + match):
        m.rpe(t, poses, good_t, good)


# --- files ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("fmt", ["tum", "kitti", "csv"])
def test_trajectory_files_round_trip(tmp_path, fmt):
    t, poses = wiggly(50)
    path = tmp_path / f"traj.{fmt}"
    write_trajectory(path, t + 1.7e9, poses, fmt)
    t2, p2 = read_trajectory(path)
    np.testing.assert_allclose(p2, poses, atol=1e-9)
    if fmt == "kitti":
        np.testing.assert_array_equal(t2, np.arange(50.0))
    else:
        np.testing.assert_allclose(t2, t + 1.7e9, atol=1e-6)


def test_kitti_line_is_the_embedded_matrix(tmp_path):
    path = tmp_path / "k.txt"
    write_trajectory(path, [0.0], [[1.0, 2.0, math.pi / 2]], "kitti")
    vals = [float(v) for v in path.read_text().split()]
    np.testing.assert_allclose(vals, [0, -1, 0, 1, 1, 0, 0, 2, 0, 0, 1, 0], atol=1e-12)


def test_integer_nanoseconds_are_written_exactly(tmp_path):
    path = tmp_path / "t.tum"
    write_trajectory(
        path, np.array([1_700_000_000_123_456_789, -1_500_000_000], dtype=np.int64), np.zeros((2, 3)), "tum"
    )
    lines = path.read_text().splitlines()
    assert lines[0].split()[0] == "1700000000.123456789" and lines[1].split()[0] == "-1.500000000"


def test_tum_reader_takes_the_yaw_of_any_quaternion(tmp_path):
    path = tmp_path / "q.tum"
    yaw = 2.5
    # yaw quaternion scaled by 3, with comments and blank lines around
    path.write_text(f"# t x y z qx qy qz qw\n\n0 1 2 9 0 0 {3 * math.sin(yaw / 2)} {3 * math.cos(yaw / 2)}\n")
    _, p = read_trajectory(path)
    np.testing.assert_allclose(p, [[1, 2, yaw]], atol=1e-12)


@pytest.mark.parametrize(
    "text, match",
    [
        ("", "empty"),
        ("0 1 2 3\n", "4 fields"),
        ("0 0 0 0 0 0 0 1\n1 0 0 0 0 0 0\n", "line 2: 7 fields"),
        ("0 0 0 0 0 0 0 1\n1 0 x 0 0 0 0 1\n", "line 2, field 3: not a number"),
        ("0 0 0 0 0 0 0 1\n1 0 nan 0 0 0 0 1\n", "non-finite"),
        ("0 0 0 0 0 0 0 0\n", "zero quaternion"),
        ("t,x,y\n0,0,0\n", "header t,x,y,theta"),
    ],
)
def test_bad_trajectory_files_name_file_and_line(tmp_path, text, match):
    path = tmp_path / "bad.tum"
    path.write_text(text)
    with pytest.raises(TrajectoryFileError, match=match):
        read_trajectory(path)


def test_missing_trajectory_file(tmp_path):
    with pytest.raises(TrajectoryFileError, match="no such file"):
        read_trajectory(tmp_path / "nope.tum")


# --- CLI ------------------------------------------------------------------------------------------------
def run_cli(argv):
    from omnikin.cli import metrics

    p = argparse.ArgumentParser(prog="omnikin")
    metrics.add_parser(p.add_subparsers(), "preset or robot file")
    args = p.parse_args([str(a) for a in argv])
    return args.func(args)


def test_metrics_cli_json_matches_the_library(tmp_path, capsys):
    t, ref = wiggly(120)
    est = rigid(ref, 0.2, 0.1, 0.05)
    est[:, :2] += np.random.default_rng(1).normal(0, 0.01, (120, 2))
    write_trajectory(tmp_path / "ref.tum", t, ref, "tum")
    write_trajectory(tmp_path / "est.csv", t + 0.002, est, "csv")
    assert run_cli(["metrics", tmp_path / "ref.tum", tmp_path / "est.csv", "--align", "--delta", "5", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    a = m.ate(t, ref, t + 0.002, est, align=True)
    r = m.rpe(t, ref, t + 0.002, est, delta=5)
    assert doc["ate"]["translation"]["rmse"] == pytest.approx(a.stats.rmse, abs=1e-8)
    assert doc["rpe"]["translation"]["mean"] == pytest.approx(r.translation_stats.mean, abs=1e-8)
    assert doc["rpe"]["rotation_deg"]["max"] == pytest.approx(math.degrees(r.rotation_stats.max), abs=1e-6)
    assert doc["rpe"]["pairs"] == 23 and doc["ate"]["pairs"] == 120 and doc["ate"]["aligned"]
    assert run_cli(["metrics", tmp_path / "ref.tum", tmp_path / "est.csv"]) == 0
    out = capsys.readouterr().out
    assert "ATE translation [m]" in out and "RPE rotation [deg]" in out and "120 associated poses" in out


@pytest.mark.parametrize(
    "extra, match",
    [
        (["--delta", "0"], "--delta"),
        (["--t-max-diff", "-1"], "--t-max-diff"),
        (["--t-offset", "100"], "no matching timestamps"),
    ],
)
def test_metrics_cli_refuses(tmp_path, extra, match):
    t, ref = wiggly(20)
    write_trajectory(tmp_path / "a.tum", t, ref, "tum")
    with pytest.raises(OmnikinError, match=match):
        run_cli(["metrics", tmp_path / "a.tum", tmp_path / "a.tum", *extra])


# --- evo (GPL, optional: only compared against when installed) -----------------------------------------
def _evo_case(tmp_path, seed):
    """Reference at 50 Hz; estimate at ~30 Hz with jittered stamps, a rigid offset, drift and noise."""
    rng = np.random.default_rng(seed)
    t_ref, ref = wiggly(500, seed)
    t_ref = t_ref * 0.2 + 1.7e9
    t_est = np.sort(rng.uniform(t_ref[0] - 0.1, t_ref[-1] + 0.1, 330))
    idx = np.clip(np.searchsorted(t_ref, t_est), 0, len(t_ref) - 1)
    est = rigid(ref[idx], 0.5, -0.3, 0.3)
    est[:, 2] = wrap(est[:, 2] + np.cumsum(rng.normal(0, 0.01, len(idx))))
    est[:, :2] += rng.normal(0, 0.02, (len(idx), 2))
    write_trajectory(tmp_path / "ref.tum", t_ref, ref, "tum")
    write_trajectory(tmp_path / "est.tum", t_est, est, "tum")
    return tmp_path / "ref.tum", tmp_path / "est.tum"


@pytest.mark.parametrize("seed", [0, 1])
def test_same_numbers_as_evo(tmp_path, seed):
    evo = pytest.importorskip("evo")  # noqa: F841
    from evo.core import metrics as em
    from evo.core import sync
    from evo.tools import file_interface

    ref_path, est_path = _evo_case(tmp_path, seed)
    tr, qr = read_trajectory(ref_path)
    te, pe = read_trajectory(est_path)
    eref = file_interface.read_tum_trajectory_file(str(ref_path))
    eest = file_interface.read_tum_trajectory_file(str(est_path))
    for max_diff in (0.01, 0.05):
        r, e = sync.associate_trajectories(eref, eest, max_diff=max_diff)
        i_ref, i_est = m.associate(tr, te, max_diff)
        np.testing.assert_array_equal(tr[i_ref], r.timestamps)
        np.testing.assert_array_equal(te[i_est], e.timestamps)
        for align in (False, True):
            e2 = copy.deepcopy(e)
            if align:
                e2.align(r, correct_scale=False)
            ape = em.APE(em.PoseRelation.translation_part)
            ape.process_data((r, e2))
            ours = m.ate(tr, qr, te, pe, align=align, max_diff=max_diff).stats.as_dict()
            for k, v in ape.get_all_statistics().items():
                assert ours[k] == pytest.approx(float(v), abs=1e-9, rel=1e-9), (max_diff, align, k)
        for delta, all_pairs in ((1, False), (7, False), (7, True)):
            for relation, unit, key in (
                (em.PoseRelation.translation_part, "rad", "translation_stats"),
                (em.PoseRelation.rotation_angle_rad, "rad", "rotation_stats"),
                (em.PoseRelation.rotation_angle_deg, "deg", "rotation_stats"),
            ):
                rpe = em.RPE(relation, delta=delta, delta_unit=em.Unit.frames, all_pairs=all_pairs)
                rpe.process_data((r, e))
                ours = getattr(
                    m.rpe(tr, qr, te, pe, delta=delta, all_pairs=all_pairs, angle_unit=unit, max_diff=max_diff), key
                ).as_dict()
                for k, v in rpe.get_all_statistics().items():
                    assert ours[k] == pytest.approx(float(v), abs=1e-9, rel=1e-9), (delta, all_pairs, relation, k)


def test_cli_matches_evo_main_ape(tmp_path, capsys):
    """``omnikin metrics --align --json`` against evo's command-line entry point ``main_ape``."""
    pytest.importorskip("evo")
    from evo.core import metrics as em
    from evo.core import sync
    from evo.main_ape import ape
    from evo.tools import file_interface

    ref_path, est_path = _evo_case(tmp_path, 2)
    r, e = sync.associate_trajectories(
        file_interface.read_tum_trajectory_file(str(ref_path)),
        file_interface.read_tum_trajectory_file(str(est_path)),
        max_diff=0.01,
    )
    result = ape(r, e, pose_relation=em.PoseRelation.translation_part, align=True, correct_scale=False)
    assert run_cli(["metrics", ref_path, est_path, "--align", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    for k in ("rmse", "mean", "median", "std", "min", "max", "sse"):
        assert doc["ate"]["translation"][k] == pytest.approx(float(result.stats[k]), abs=1e-9, rel=1e-9)


def test_kitti_against_a_timed_file_is_refused(tmp_path, capsys):
    """KITTI has no timestamps (pose k at t = k): pairing it with seconds would match the wrong
    poses, so the command refuses and says how to compare."""
    from omnikin.cli.main import main

    t = np.arange(50) * 0.1
    poses = np.column_stack([t, 0 * t, 0 * t])
    write_trajectory(tmp_path / "a.kitti", t, poses, "kitti")
    write_trajectory(tmp_path / "b.tum", t, poses, "tum")
    write_trajectory(tmp_path / "c.kitti", t, poses, "kitti")
    for ref, est in (("a.kitti", "b.tum"), ("b.tum", "a.kitti")):
        assert main(["metrics", str(tmp_path / ref), str(tmp_path / est)]) == 2
        err = capsys.readouterr().err
        assert "a.kitti is KITTI (no timestamps" in err and "b.tum has timestamps" in err
    assert main(["metrics", str(tmp_path / "a.kitti"), str(tmp_path / "c.kitti"), "--json"]) == 0  # by index


def test_written_files_have_no_negative_zero(tmp_path):
    """-0.0 poses (e.g. x = -0.0 after a sign flip) are written as 0, not '-0'."""
    for fmt in ("tum", "kitti", "csv"):
        path = tmp_path / f"z.{fmt}"
        write_trajectory(path, [0.0, 1.0], [[-0.0, -0.0, -0.0], [1.0, -0.0, 0.0]], fmt)
        text = path.read_text()
        assert "-0 " not in text + " " and "-0." not in text and "-0\n" not in text, (fmt, text)
