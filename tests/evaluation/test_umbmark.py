"""UMBmark analysis (Tomasi & Todt eq. 3-6), Borenstein's correction and the least-squares calibration.

Hand values: the centres of gravity and distances below are worked out by hand; Borenstein's
figures for x_cw = -0.12 m, x_ccw = 0.04 m, L = 4 m, b = 0.33 m were computed with 30-digit
arithmetic from the formulas of docs/conventions.md:
alpha = 0.005, beta = 0.01, R = 2 / sin(0.005) = 400.0016666715, E_d = 400.1666.../399.8366...
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnikin import OmnikinError, load_robot
from omnikin.evaluation.calibration import (
    borenstein_calibrate,
    least_squares_calibration,
    predicted_end,
    recommended_runs,
)
from omnikin.evaluation.umbmark import analyze, borenstein, differential_pair, simulate_umbmark
from omnikin.motion.plans import CalibrationRun, line, spin, umbmark_square
from omnikin.simulation.error_models import NOISE, PROFILES, NoiseModel, SystematicErrors, WheelErrors
from omnikin.simulation.kinematic import simulate_kinematic

EXACT = NoiseModel(quantise=False)
SIGMA = (0.001, math.radians(0.2))
DIFF_TRACK = 0.33


@pytest.fixture(scope="module")
def diff():
    return load_robot("diff-drive")


def e_max_syst(true, model):
    """E_max,syst without random errors (one run per direction suffices)."""
    return simulate_umbmark(true, model, noise=NOISE["none"], runs=1)[0].e_max_syst


# =====================================================================================================
# analyze: eq. 3-6
# =====================================================================================================
CW = [(0.010, -0.020, 0.01), (0.014, -0.016, 0.02), (0.012, -0.030, float("nan"))]
CCW = [(-0.03, 0.04, 0.0), (-0.01, 0.02, 0.0), (-0.05, 0.06, 0.0)]


def test_analyze_hand_values():
    res = analyze(CW, CCW)
    # eq. 3-4: x_cg = mean eps_x, y_cg = mean eps_y
    np.testing.assert_allclose(res.cw.cg, [0.012, -0.022], rtol=0, atol=1e-15)
    np.testing.assert_allclose(res.ccw.cg, [-0.03, 0.04], rtol=0, atol=1e-15)
    # eq. 5-6: r_cg = sqrt(x_cg^2 + y_cg^2): sqrt(0.000628) and sqrt(0.0025)
    assert res.cw.r_cg == pytest.approx(math.sqrt(0.000628), rel=1e-12)
    assert res.ccw.r_cg == pytest.approx(0.05, rel=1e-12)
    assert res.e_max_syst == pytest.approx(0.05, rel=1e-12)
    assert res.borenstein is None
    # the larger one wins whichever direction it is in
    assert analyze(CCW, CW).e_max_syst == pytest.approx(0.05, rel=1e-12)
    swapped = analyze([(0.3, 0.4)], [(0.0, 0.1)])
    assert swapped.e_max_syst == pytest.approx(0.5) and swapped.cw.r_cg == pytest.approx(0.5)
    # (n, 2) input: heading column absent
    res2 = analyze(np.array(CW)[:, :2], np.array(CCW)[:, :2])
    assert res2.e_max_syst == pytest.approx(0.05, rel=1e-12)
    assert res2.cw.epsilon.shape == (3, 3)
    # heading NaN (not measured) is kept and reported as null
    d = res.as_dict()
    assert d["cw"]["runs"][2]["epsilon"][2] is None
    assert d["e_max_syst"] == pytest.approx(0.05)
    assert [len(r["epsilon"]) for r in d["cw"]["runs"]] == [3, 3, 3]


def test_analyze_single_run_and_side():
    res = analyze([(0.003, 0.004, 0.0)], [(-0.006, -0.008, 0.0)], side=2.0)
    assert res.cw.r_cg == pytest.approx(0.005) and res.ccw.r_cg == pytest.approx(0.010)
    assert res.side == 2.0


@pytest.mark.parametrize(
    "cw, ccw, match",
    [
        (CW, [], "ccw"),  # a single direction
        (CW, np.zeros((0, 3)), "ccw"),  # zero runs
        (np.zeros((0, 2)), CCW, "cw"),
        (CW, None, "ccw"),
        ([(0.01, float("nan"), 0.0)], CCW, "cw"),  # NaN position
        (CW, [(float("inf"), 0.0)], "ccw"),
        ([0.01, 0.02, 0.03], CCW, "cw"),  # wrong shapes
        (CW, np.zeros((2, 4)), "ccw"),
        (np.zeros((2, 1)), CCW, "cw"),
        (np.zeros((2, 2, 3)), CCW, "cw"),
    ],
)
def test_analyze_errors(cw, ccw, match):
    with pytest.raises(OmnikinError, match=match):
        analyze(cw, ccw)


def test_analyze_bad_side_and_mode():
    for side in (0.0, -4.0, float("nan")):
        with pytest.raises(OmnikinError):
            analyze(CW, CCW, side=side)
    with pytest.raises(OmnikinError):
        analyze(CW, CCW, mode="slide")


# =====================================================================================================
# Borenstein
# =====================================================================================================
def test_borenstein_hand_values():
    b = borenstein(-0.12, 0.04, 4.0, 0.33)
    assert b.alpha == pytest.approx(0.005, rel=1e-12)
    assert b.beta == pytest.approx(0.01, rel=1e-12)
    assert b.R == pytest.approx(400.001666671527790591964, rel=1e-12)
    assert b.E_d == pytest.approx(1.00082533701260344957816508388, rel=1e-13)
    assert b.E_b == pytest.approx(1.0031932633347242160861427288, rel=1e-13)
    assert b.c_L == pytest.approx(0.999587501718747851563778831401, rel=1e-13)
    assert b.c_R == pytest.approx(1.0004124982812521484362211686, rel=1e-13)
    assert b.b_new == pytest.approx(0.331053776900458991308427100502, rel=1e-13)
    # c_R / c_L = E_d (diameter ratio) and (c_L + c_R) / 2 = 1 (mean diameter kept)
    assert b.c_R / b.c_L == pytest.approx(b.E_d, rel=1e-13)
    assert (b.c_L + b.c_R) / 2 == pytest.approx(1.0, rel=1e-13)
    assert set(b.as_dict()) == {"alpha", "beta", "R", "E_d", "E_b", "c_L", "c_R", "b_new"}


def test_borenstein_special_cases():
    # x_cw = x_ccw: only corner error (beta = 0, straight legs): R infinite, E_d = 1
    b = borenstein(-0.08, -0.08, 4.0, 0.33)
    assert b.beta == 0.0 and math.isinf(b.R)
    assert b.E_d == 1.0 and b.c_L == 1.0 and b.c_R == 1.0
    assert b.alpha == pytest.approx(0.01)
    assert b.E_b == pytest.approx((math.pi / 2) / (math.pi / 2 - 0.01), rel=1e-14)
    # x_cw = -x_ccw: only leg curvature (alpha = 0): E_b = 1, b_new = b
    b = borenstein(-0.16, 0.16, 4.0, 0.33)
    assert b.alpha == 0.0 and b.E_b == 1.0 and b.b_new == pytest.approx(0.33)
    assert b.beta == pytest.approx(0.02)
    # beta < 0: curving right, right wheel smaller: E_d < 1
    assert borenstein(0.16, -0.16, 4.0, 0.33).E_d < 1.0


def test_borenstein_only_for_differential_drive(tomasi, diff):
    assert analyze(CW, CCW, robot=tomasi).borenstein is None
    left, right, track = differential_pair(diff)
    assert (left.name, right.name) == ("left", "right") and track == pytest.approx(DIFF_TRACK)
    res = analyze(CW, CCW, robot=diff)
    expected = borenstein(0.012, -0.03, 4.0, DIFF_TRACK)
    assert res.borenstein.as_dict() == pytest.approx(expected.as_dict(), rel=1e-12)
    assert analyze(CW, CCW, side=2.0, robot=diff).borenstein.alpha == pytest.approx((0.012 - 0.03) / -8.0)
    assert differential_pair(tomasi) is None


def test_borenstein_by_simulation_track_error(diff):
    """True track 1 % larger: every corner turns 90 deg / 1.01 (under-rotation, alpha > 0); E_b = 1.01."""
    d = 0.005 * DIFF_TRACK
    true = SystematicErrors({"left": WheelErrors(dy=d), "right": WheelErrors(dy=-d)}).apply(diff)
    assert differential_pair(true)[2] == pytest.approx(1.01 * DIFF_TRACK, rel=1e-14)
    res = simulate_umbmark(true, diff, noise=NOISE["none"], runs=1)[0]
    b = res.borenstein
    assert b.alpha > 0
    assert b.E_b == pytest.approx(1.01, rel=0.002)
    assert abs(b.beta) < 1e-9 and b.E_d == pytest.approx(1.0, abs=1e-9)
    # first order: x_cw = x_ccw = -2 L alpha with alpha = 90 deg (1 - 1/1.01)
    alpha = math.pi / 2 * (1 - 1 / 1.01)
    assert res.cw.cg[0] == pytest.approx(-8 * alpha, rel=0.05)
    assert res.ccw.cg[0] == pytest.approx(res.cw.cg[0], rel=1e-9)


def test_borenstein_by_simulation_wheel_diameter_error(diff):
    """Right wheel 0.1 % larger: straight legs curve left (beta > 0), E_d = D_R / D_L = 1.001."""
    true = SystematicErrors({"right": WheelErrors(radius=0.001)}).apply(diff)
    b = simulate_umbmark(true, diff, noise=NOISE["none"], runs=1)[0].borenstein
    assert b.beta > 0
    assert b.E_d == pytest.approx(1.001, abs=2e-4)
    assert b.c_R > 1 > b.c_L
    # and the mirror image
    true = SystematicErrors({"left": WheelErrors(radius=0.001)}).apply(diff)
    b = simulate_umbmark(true, diff, noise=NOISE["none"], runs=1)[0].borenstein
    assert b.beta < 0
    assert b.E_d == pytest.approx(1 / 1.001, abs=2e-4)


def test_borenstein_calibrate_iterated(diff):
    true = SystematicErrors(
        {"left": WheelErrors(radius=-0.002, dy=0.002), "right": WheelErrors(radius=0.003, dy=-0.001)}
    ).apply(diff)
    model = diff
    res = simulate_umbmark(true, model, noise=NOISE["none"], runs=1)[0]
    before = res.e_max_syst
    assert before > 0.1
    for _ in range(3):
        model = borenstein_calibrate(model, res)
        res = simulate_umbmark(true, model, noise=NOISE["none"], runs=1)[0]
    assert res.e_max_syst <= before / 10
    # the corrected model keeps the axle midpoint and the wheel names
    left, right, track = differential_pair(model)
    assert (left.name, right.name) == ("left", "right")
    assert 0.5 * (left.y + right.y) == pytest.approx(0.0, abs=1e-15)


def test_borenstein_calibrate_refuses_other_robots(tomasi):
    res = simulate_umbmark(tomasi, tomasi, noise=NOISE["none"], runs=1)[0]
    with pytest.raises(OmnikinError, match="differential"):
        borenstein_calibrate(tomasi, res)


# =====================================================================================================
# simulate_umbmark
# =====================================================================================================
def test_run_umbmark_translate_on_non_holonomic_robot(diff):
    with pytest.raises(OmnikinError, match="translate"):
        simulate_umbmark(diff, diff, mode="translate")


def test_run_umbmark_shapes_and_bad_runs(tomasi):
    results = simulate_umbmark(tomasi, tomasi, runs=3, trials=2, noise=NOISE["typical"], rng=1, rate=20.0)
    assert len(results) == 2
    for r in results:
        assert r.cw.epsilon.shape == (3, 3) and r.ccw.epsilon.shape == (3, 3)
    again = simulate_umbmark(tomasi, tomasi, runs=3, trials=2, noise=NOISE["typical"], rng=1, rate=20.0)
    assert [r.e_max_syst for r in again] == [r.e_max_syst for r in results]
    results, sims = simulate_umbmark(tomasi, tomasi, runs=2, trials=1, rng=1, rate=20.0, keep_runs=True)
    assert set(sims) == {"cw", "ccw"} and sims["cw"].truth.shape[0] == 2
    for bad in (0, -1, 1.5):
        with pytest.raises(OmnikinError):
            simulate_umbmark(tomasi, tomasi, runs=bad)


# =====================================================================================================
# least-squares calibration
# =====================================================================================================
def calibration_runs(true, robot, noise, rng, repeats=1, plans=None):
    runs = []
    for label, plan in plans or recommended_runs(robot):
        sim = simulate_kinematic(plan, true, robot, noise=noise, trials=repeats, rng=rng, keep_truth=False)
        runs += [CalibrationRun(plan, tuple(m), label, SIGMA) for m in sim.measured]
    return runs


INJECTED = {
    "tomasi-omni3": {
        "w1": WheelErrors(radius=0.008, drive=0.01, dx=0.002),
        "w2": WheelErrors(radius=-0.005, dy=0.001),
        "w3": WheelErrors(radius=0.003, drive=-0.005),
    },
    "diff-drive": {"left": WheelErrors(radius=-0.004, dy=0.002), "right": WheelErrors(radius=0.006, dy=-0.001)},
}


@pytest.mark.parametrize("name", sorted(INJECTED))
def test_calibration_round_trip_known_errors(name):
    robot = load_robot(name)
    injected = SystematicErrors(INJECTED[name])
    true = injected.apply(robot)
    cal = least_squares_calibration(robot, calibration_runs(true, robot, EXACT, 0))
    for wheel, e in INJECTED[name].items():
        est = cal.errors.wheels[wheel].radius
        assert abs(est - e.radius) <= 1e-3 * abs(e.radius), (wheel, est, e.radius)
    assert cal.identifiability.blind == []
    assert cal.residual_after < cal.residual_before
    before, after = e_max_syst(true, robot), e_max_syst(true, cal.robot)
    assert after <= before / 20, (before, after)
    # the calibrated robot keeps the nominal name and wheel names, and its radii are the true ones
    assert cal.robot.name == robot.name
    for w in true.rolling:
        if w.encoder is not None:
            assert cal.robot.wheel(w.name).radius == pytest.approx(w.radius, rel=1e-5)


@pytest.mark.parametrize("name", sorted(INJECTED))
def test_calibration_round_trip_with_measurement_noise(name):
    """Measured end poses with 1 mm / 0.2 deg noise (three repeats): the radius estimates land within
    a few of the reported posterior sigmas (about 1.5e-4) of the injected values."""
    robot = load_robot(name)
    true = SystematicErrors(INJECTED[name]).apply(robot)
    noise = NoiseModel(quantise=False, measurement=SIGMA[0], measurement_theta=SIGMA[1])
    cal = least_squares_calibration(robot, calibration_runs(true, robot, noise, np.random.default_rng(0), repeats=3))
    for wheel, e in INJECTED[name].items():
        sigma = cal.identifiability.sigma[f"{wheel}.radius"]
        assert 5e-5 < sigma < 1e-3
        assert abs(cal.errors.wheels[wheel].radius - e.radius) < 5 * sigma
    assert cal.residual_after < 2.0  # in measurement sigmas: the model fits to the noise


@pytest.mark.parametrize("name", sorted(INJECTED))
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_calibration_typical_profile_and_noise(name, seed):
    robot = load_robot(name)
    true = PROFILES["typical"].sample(robot, seed).apply(robot)
    runs = calibration_runs(true, robot, NOISE["typical"], np.random.default_rng(1000 + seed), repeats=3)
    cal = least_squares_calibration(robot, runs)
    before, after = e_max_syst(true, robot), e_max_syst(true, cal.robot)
    assert after <= before / 20, (before, after)


def test_predicted_end_matches_simulation(tomasi, diff):
    """The closed-form prediction of the calibration equals the sampled simulation (noise-free)."""
    for robot, seed in ((tomasi, 4), (diff, 5)):
        true = PROFILES["typical"].sample(robot, seed).apply(robot)
        for _, plan in recommended_runs(robot):
            sim = simulate_kinematic(plan, true, robot, noise=EXACT, rate=50.0)
            got = predicted_end(plan, true, robot)
            np.testing.assert_allclose(got[:2], sim.measured[0, :2], atol=1e-9)
            assert abs((got[2] - sim.measured[0, 2] + math.pi) % (2 * math.pi) - math.pi) < 1e-9


def test_identifiability_translate_squares_blind_to_radius_scale(tomasi):
    """A common radius scale (1 + e) scales every translation leg and leaves the heading alone: the
    'translate' square closes exactly, so those two runs cannot see the scale."""
    true = SystematicErrors({n: WheelErrors(radius=0.01) for n in ("w1", "w2", "w3")}).apply(tomasi)
    plans = [(f"square {d} translate", umbmark_square(d, 4.0, "translate")) for d in ("cw", "ccw")]
    runs = calibration_runs(true, tomasi, EXACT, 0, plans=plans)
    for run in runs:
        np.testing.assert_allclose(run.measured, 0.0, atol=1e-9)
    cal = least_squares_calibration(tomasi, runs)
    ident = cal.identifiability
    assert ident.blind, "the common radius scale must be reported as not observable"
    names = ident.parameters
    # the reported blind directions span the common radius scale (1, 1, 1 on the radii) / sqrt(3)
    basis = np.zeros((len(ident.blind), len(names)))
    for k, combo in enumerate(ident.blind):
        for c in combo:
            basis[k, names.index(c["parameter"])] = c["weight"]
    scale = np.array([1.0 if n.endswith(".radius") else 0.0 for n in names]) / math.sqrt(3)
    q, _ = np.linalg.qr(basis.T)
    assert np.linalg.norm(q.T @ scale) > 0.95
    # every blind direction names at least one parameter; the radii appear among them
    assert all(combo for combo in ident.blind)
    assert {"w1.radius", "w2.radius", "w3.radius"} <= {c["parameter"] for combo in ident.blind for c in combo}
    # the prior keeps the blind scale at zero rather than inventing a value
    for w in ("w1", "w2", "w3"):
        assert abs(cal.errors.wheels[w].radius) < 1e-6


def test_identifiability_matches_independent_jacobian(tomasi):
    """The reported singular values (residuals in measurement sigmas per prior sigma) and posterior sigmas
    against a Jacobian built here: central differences of the predicted end poses in each wheel's radius,
    radial hub shift (lever, normal to the roller axis) and drive direction, at the true parameters
    (all radii +1 %), scaled by the measurement sigmas and the prior sigmas (5 %, 10 mm, 5 deg)."""
    base = {n: {"radius": 0.01} for n in ("w1", "w2", "w3")}
    true = SystematicErrors({n: WheelErrors(**e) for n, e in base.items()}).apply(tomasi)
    protocol = recommended_runs(tomasi)
    cal = least_squares_calibration(tomasi, calibration_runs(true, tomasi, EXACT, 0, plans=protocol))
    prior = {"radius": 0.05, "lever": 0.01, "drive": math.radians(5.0)}
    cols, h = [], 1e-5
    for w, b in zip(("w1", "w2", "w3"), np.radians([0.0, 120.0, 240.0]), strict=True):
        for par in ("radius", "lever", "drive"):
            ends = []
            for sgn in (1, -1):
                e = dict(base[w])
                if par == "radius":
                    e["radius"] += sgn * h
                elif par == "lever":
                    e.update(dx=sgn * h * math.cos(b), dy=sgn * h * math.sin(b))
                else:
                    e["drive"] = sgn * h
                cand = SystematicErrors({**{n: WheelErrors(**v) for n, v in base.items()}, w: WheelErrors(**e)})
                ends.append(np.array([predicted_end(p, cand.apply(tomasi), tomasi) for _, p in protocol]))
            d = (ends[0] - ends[1]) / (2 * h) / [SIGMA[0], SIGMA[0], SIGMA[1]]
            cols.append(d.ravel() * prior[par])
    jac = np.column_stack(cols)
    assert cal.identifiability.parameters == [
        f"{w}.{p}" for w in ("w1", "w2", "w3") for p in ("radius", "lever", "drive")
    ]
    own = np.linalg.svd(jac, compute_uv=False)
    np.testing.assert_allclose(cal.identifiability.singular_values, own, rtol=1e-3)
    scale = np.tile([prior[p] for p in ("radius", "lever", "drive")], 3)
    post = np.sqrt(np.diag(np.linalg.inv(jac.T @ jac + np.eye(9)))) * scale  # prior rows: q ~ N(0, 1)
    np.testing.assert_allclose([cal.identifiability.sigma[n] for n in cal.identifiability.parameters], post, rtol=1e-2)


@pytest.mark.parametrize("name", ["tomasi-omni3", "diff-drive"])
def test_identifiability_full_runs_no_blind_direction(name):
    robot = load_robot(name)
    true = SystematicErrors({w.name: WheelErrors(radius=0.01) for w in robot.rolling if w.encoder}).apply(robot)
    cal = least_squares_calibration(robot, calibration_runs(true, robot, EXACT, 0))
    assert cal.identifiability.blind == []
    for w in robot.rolling:
        if w.encoder is not None:
            assert cal.errors.wheels[w.name].radius == pytest.approx(0.01, rel=1e-3)


def test_recommended_runs_and_calibrate_errors(tomasi, diff):
    labels = [lbl for lbl, _ in recommended_runs(tomasi)]
    assert "square cw translate 4" in labels and "square ccw rotate 4" in labels
    assert all("translate" not in lbl for lbl, _ in recommended_runs(diff))
    with pytest.raises(OmnikinError):
        least_squares_calibration(tomasi, [])
    with pytest.raises(OmnikinError):
        CalibrationRun(line(1.0), (float("nan"), 0.0, 0.0))
    # heading not measured is allowed
    CalibrationRun(spin(1.0), (0.0, 0.0, float("nan")))


# =====================================================================================================
# runs the robot cannot drive; the recommended runs
# =====================================================================================================
def simulate_refusal(plan, robot):
    """The reason ``simulate`` gives for refusing ``plan`` on ``robot`` (what calibration must say too)."""
    from omnikin.errors import InfeasibleTwistError

    with pytest.raises(InfeasibleTwistError) as info:
        simulate_kinematic(plan, robot, robot, noise=EXACT, rate=20.0)
    return str(info.value).split(" (on_infeasible=")[0].removeprefix(f"robot {robot.name!r}: ")


@pytest.mark.parametrize(
    "robot_name, path, wheel",
    [
        ("diff-drive", "line 1 90", "left"),  # sideways: the fixed wheels would slide
        ("ackermann", "spin 90", "front_left"),  # in place: beyond the steering limits
        ("ackermann", "square cw rotate 4", "front_left"),
    ],
)
def test_calibrate_refuses_a_run_the_robot_cannot_drive_naming_it(robot_name, path, wheel):
    from omnikin.errors import InfeasibleRunError
    from omnikin.motion.plans import parse_plan

    robot = load_robot(robot_name)
    good = CalibrationRun(line(4.0), (4.0, 0.0, 0.0), "line 4")
    bad = CalibrationRun(parse_plan(path), (0.0, 1.0, 0.0), path)
    with pytest.raises(InfeasibleRunError) as info:
        least_squares_calibration(robot, [good, good, bad])
    message = str(info.value)
    assert info.value.run == 2
    assert message.startswith(f"run 3 ('{path}'): robot '{robot_name}' cannot drive this path: "), message
    assert wheel in message and "\n" not in message
    # the same check as simulate: its reason, word for word
    assert simulate_refusal(parse_plan(path), robot) in message


def test_calibrate_names_the_file_line_of_an_infeasible_run(tmp_path):
    from omnikin.errors import InfeasibleRunError
    from omnikin.io.runs import read_calibration_runs

    f = tmp_path / "runs.csv"
    f.write_text("path,x_abs,y_abs\n# sideways below\nline 4,4.0,0\n\nline 1 90,0,1\n", encoding="utf-8")
    with pytest.raises(InfeasibleRunError, match=r"runs\.csv: line 5 \('line 1 90'\): robot 'diff-drive' cannot drive"):
        least_squares_calibration(load_robot("diff-drive"), read_calibration_runs(f))


@pytest.mark.parametrize(
    "name",
    [
        "tomasi-omni3",
        "diff-drive",
        "ackermann",
        "villasenor-omni3",
        "synchro",
        "xr4000",
        "mecanum4",
        "omni4",
        "garcia-sillas-omni3",
    ],
)
def test_recommended_runs_are_drivable_and_read_back_from_their_text(name):
    from omnikin.motion.plans import parse_plan

    robot = load_robot(name)
    runs = recommended_runs(robot, 2.5)
    assert runs
    for text, plan in runs:
        assert parse_plan(text) == plan
        simulate_kinematic(plan, robot, robot, noise=EXACT, rate=10.0)  # refuses what the robot cannot drive
    texts = [t for t, _ in runs]
    if robot.mobility.holonomic and name != "villasenor-omni3":
        assert "square cw translate 2.5" in texts and "line 2.5 90" in texts
    if name == "diff-drive":
        assert not any("translate" in t or t == "line 2.5 90" for t in texts)
    if name == "ackermann":  # cannot turn in place: half circles instead
        assert texts == ["line 2.5 0", "arc 1.25 180", "arc 1.25 -180"]


def test_steering_offsets_of_steerable_wheels_are_calibrated():
    """A steerable wheel's steering offset ('drive') is a fitted parameter: with it missing the fit
    compensated with metre-sized hub shifts and made UMBmark ten times worse (synchro)."""
    robot = load_robot("synchro")
    injected = {
        "w1": WheelErrors(radius=0.003, drive=0.009),
        "w2": WheelErrors(radius=-0.002, drive=-0.006),
        "w3": WheelErrors(dx=0.001, drive=0.004),
    }
    true = SystematicErrors(injected).apply(robot)
    cal = least_squares_calibration(robot, calibration_runs(true, robot, EXACT, 0))
    assert {"w1.drive", "w2.drive", "w3.drive"} <= set(cal.values)
    assert cal.fits and cal.residual_after < 0.1  # noise-free runs: the model explains them
    assert e_max_syst(true, cal.robot) <= e_max_syst(true, robot) / 100


def test_a_calibration_that_cannot_explain_its_runs_says_so(tomasi):
    """Runs whose measurements no wheel errors can produce (a half turn measured as a 4 m line)."""
    from omnikin.evaluation.calibration import FIT_LIMIT

    runs = calibration_runs(tomasi, tomasi, EXACT, 0)
    runs[3] = CalibrationRun(runs[3].plan, (4.0, 0.0, 0.0), runs[3].label, SIGMA)
    cal = least_squares_calibration(tomasi, runs)
    assert cal.residual_after > FIT_LIMIT and not cal.fits
    assert cal.as_dict()["fits"] is False


def test_fitted_parameters_carry_their_units(tomasi):
    true = SystematicErrors(INJECTED["tomasi-omni3"]).apply(tomasi)
    cal = least_squares_calibration(tomasi, calibration_runs(true, tomasi, EXACT, 0))
    units = {p["name"]: p["unit"] for p in cal.parameters()}
    assert units == {
        f"{w}.{k}": u for w in ("w1", "w2", "w3") for k, u in (("radius", "relative"), ("lever", "m"), ("drive", "rad"))
    }
    values = {p["name"]: p["value"] for p in cal.parameters()}
    # the lever of w2 is its hub shift normal to the roller axis: dy = 1 mm rotated into that direction
    w2 = tomasi.wheel("w2")
    a = w2.drive + w2.roller
    assert values["w2.lever"] == pytest.approx(math.cos(a) * 0.001, abs=2e-5)
    assert values["w1.radius"] == pytest.approx(0.008, rel=1e-3)


def test_budget_estimate_counts_what_a_trial_really_simulates():
    """Each extra trial drives 'runs' squares per direction before and after calibration: the
    estimate grows by at least that many sampled steps (from the sampler itself) and by little
    more (the estimator bounds each segment from above by at most one sample)."""
    from omnikin.evaluation.procedure import estimate_cost
    from omnikin.motion.timing import sample_plan

    robot = load_robot("tomasi-omni3")
    for rate, runs in ((20.0, 3), (100.0, 5)):
        opts = dict(side=4.0, mode="rotate", runs=runs, rate=rate, calibrate=True)
        one, two = estimate_cost(robot, trials=1, **opts), estimate_cost(robot, trials=2, **opts)
        square = len(sample_plan(umbmark_square("cw"), robot, rate).t)
        actual = 2 * 2 * runs * square  # two directions, before and after
        slack = 2 * 2 * runs * (len(umbmark_square("cw").segments) + 1)
        assert actual <= two.samples - one.samples <= actual + slack
        assert two.bytes > one.bytes and two.seconds > one.seconds


# --- straight legs: beta = 0 ---------------------------------------------------------------------------
def test_borenstein_straight_legs_give_ed_exactly_one():
    """x_cw = x_ccw = +10 mm: beta = (x_cw - x_ccw) / (-4L) = 0, the legs do not curve (R infinite),
    E_d = 1 and c_L = c_R = 1 exactly; alpha = 0.02 / (-16) = -0.00125 rad, E_b = (pi/2) / (pi/2 + 0.00125)."""
    b = borenstein(0.01, 0.01, 4.0, DIFF_TRACK)
    assert b.beta == 0.0 and math.copysign(1.0, b.beta) == 1.0  # not -0
    assert b.straight and b.R == math.inf
    assert (b.E_d, b.c_L, b.c_R) == (1.0, 1.0, 1.0)
    assert b.alpha == pytest.approx(-0.00125, rel=1e-15)
    assert b.E_b == pytest.approx((math.pi / 2) / (math.pi / 2 + 0.00125), rel=1e-15)
    assert b.b_new == pytest.approx(DIFF_TRACK * (math.pi / 2) / (math.pi / 2 + 0.00125), rel=1e-15)
    assert b.as_dict()["R"] is None
    assert "R straight legs" in b.describe() and "-0 " not in b.describe()
    # a curvature below the smallest float's reach: still straight, never inf/inf
    tiny = borenstein(1e-320, -1e-320, 4.0, DIFF_TRACK)
    assert tiny.E_d == 1.0 and tiny.c_L == 1.0


def test_umbmark_analyze_of_straight_legs_prints_valid_json_and_text(tmp_path, capsys):
    import json

    from omnikin.cli.main import main

    f = tmp_path / "m.csv"
    pairs = ((0.0, 0.001), (0.5, -0.001), (1.0, -3e-9))  # mean y: -1e-9 m, printed as 0.00 mm
    rows = [f"{d},{0.01 + e},{dy},{e},0" for d in ("cw", "ccw") for e, dy in pairs]
    f.write_text("direction,x_abs,y_abs,x_calc,y_calc\n" + "\n".join(rows) + "\n")
    assert main(["umbmark", "analyze", str(f), "--robot", "diff-drive", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    bor = doc["borenstein"]
    assert bor["R"] is None and bor["E_d"] == 1.0 and bor["beta"] == 0.0 and bor["c_L"] == bor["c_R"] == 1.0
    assert bor["alpha"] == pytest.approx(-0.00125, rel=1e-12)
    assert main(["umbmark", "analyze", str(f), "--robot", "diff-drive"]) == 0
    out = capsys.readouterr().out
    assert "R straight legs (beta = 0)" in out and "beta 0 rad" in out and "inf" not in out and "-0 " not in out
    assert "y = 0.00 mm" in out and "= -0.00" not in out


def test_calibration_plan_side_has_the_umbmark_bounds():
    from omnikin import calibration_plan

    for side in (1e-300, 0.049, 101.0, float("nan")):
        with pytest.raises(OmnikinError, match=r"^side \(--side\): the side of the UMBmark square must"):
            calibration_plan("diff-drive", side)
    assert calibration_plan("diff-drive", 0.05)[0] == "square cw rotate 0.05"
