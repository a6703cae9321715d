"""Inverse/forward kinematics of the robot model against closed forms and reference tables."""

import math

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from omnikin import Encoder, InfeasibleTwistError, InputError, Robot, SingularLayoutError, Steer, Wheel, load_robot
from omnikin.errors import OmnikinError
from support.counting import CountedName
from support.kinematics import circle_wheels, omni_robot

# --- ros2_controllers parity --------------------------------------------------------------
# omni_wheel_drive_controller (test vectors: robot radius 0.5 m, wheel radius 0.1 m, twist (1, 1, 1)).
# Their wheel k sits at angle offset + 2 pi k / n on the robot circle and their positive wheel speed
# drives the hub along the *clockwise* tangent. omnikin's default drive direction is the
# counter-clockwise tangent, so the mapping is: same wheel angles, omnikin speed = -(their speed).


@pytest.mark.parametrize(
    "n, offset, theirs",
    [
        (3, 0.0, [-15.0, 8.66025, -8.66025]),
        (4, math.pi / 4, [-5.0, 9.14214, -5.0, -19.1421]),
    ],
)
def test_ros2_omni_wheel_drive_controller_parity(n, offset, theirs):
    robot = omni_robot([math.degrees(offset + 2 * math.pi * k / n) for k in range(n)], distance=0.5, radius=0.1)
    ours = robot.ik([1.0, 1.0, 1.0]).wheel_speeds
    np.testing.assert_allclose(-ours, theirs, atol=1e-4)


def test_ros2_mecanum_drive_controller_parity():
    """mecanum_drive_controller: twist (10, 5, 3), wheel radius 0.5, k = lx + ly = 1 ->
    front_left 4, front_right 36, rear_right 16, rear_left 24 (their order, their k).

    Their rows: fl = (vx - vy - k w)/r, fr = (vx + vy + k w)/r, rr = (vx - vy + k w)/r,
    rl = (vx + vy - k w)/r. In omnikin's convention these are mecanum wheels driving along +x
    (drive_deg 0) with roller_deg -45 (fl, rr) and +45 (fr, rl)."""
    lx, ly, r = 0.6, 0.4, 0.5
    wheels = (
        Wheel("fl", "mecanum", lx, ly, 0.0, r, math.radians(-45)),
        Wheel("fr", "mecanum", lx, -ly, 0.0, r, math.radians(45)),
        Wheel("rr", "mecanum", -lx, -ly, 0.0, r, math.radians(-45)),
        Wheel("rl", "mecanum", -lx, ly, 0.0, r, math.radians(45)),
    )
    speeds = Robot("ros2-mecanum", wheels).ik([10.0, 5.0, 3.0]).wheel_speeds
    np.testing.assert_allclose(speeds, [4.0, 36.0, 16.0, 24.0], atol=1e-12)


def test_preset_mecanum4_matches_ros2_formula():
    robot = load_robot("mecanum4")
    lx, ly, r = 0.2355, 0.15, 0.0475
    vx, vy, w = 0.3, -0.2, 0.7
    k = lx + ly
    expected = np.array([vx - vy - k * w, vx + vy + k * w, vx + vy - k * w, vx - vy + k * w]) / r
    np.testing.assert_allclose(robot.ik([vx, vy, w]).wheel_speeds, expected, atol=1e-12)


# --- closed forms ------------------------------------------------------------------------------------
def test_radial_omni_row_closed_form(tomasi):
    """conventions: omega_i = (-sin b vx + cos b vy + l omega) / r for a radial-axle omni wheel."""
    dist, r = 0.113, 0.04125
    for i, b in enumerate(np.radians([0, 120, 240])):
        np.testing.assert_allclose(tomasi.ik_matrix[i], [-math.sin(b) / r, math.cos(b) / r, dist / r], atol=1e-12)


def test_world_frame_ik_uses_heading(tomasi):
    th = 0.7
    world = np.array([0.3, -0.1, 0.4])
    body = np.array([math.cos(th) * 0.3 + math.sin(th) * -0.1, -math.sin(th) * 0.3 + math.cos(th) * -0.1, 0.4])
    np.testing.assert_allclose(tomasi.ik(world, heading=th).wheel_speeds, tomasi.ik(body).wheel_speeds, atol=1e-12)


def test_roller_speeds_solve_hub_velocity_balance():
    """Hub velocity = r w u + s n (n normal to the roller axis): solve for (w, s) independently."""
    robot = load_robot("mecanum4")
    twist = np.array([0.4, -0.3, 0.9])
    speeds = robot.ik(twist).wheel_speeds
    rollers = robot.roller_speeds(twist)
    for w, wi, si in zip(robot.wheels, speeds, rollers, strict=True):
        v = np.array([twist[0] - twist[2] * w.y, twist[1] + twist[2] * w.x])
        u = np.array([math.cos(w.drive), math.sin(w.drive)])
        a = w.drive + w.roller
        n = np.array([-math.sin(a), math.cos(a)])
        sol = np.linalg.solve(np.column_stack([w.radius * u, n]), v)
        np.testing.assert_allclose([wi, si], sol, atol=1e-12)


def test_omni_roller_speed_is_side_velocity(tomasi):
    twist = np.array([0.2, 0.1, -0.5])
    for w, s in zip(tomasi.wheels, tomasi.roller_speeds(twist), strict=True):
        v = np.array([twist[0] - twist[2] * w.y, twist[1] + twist[2] * w.x])
        assert s == pytest.approx(-math.sin(w.drive) * v[0] + math.cos(w.drive) * v[1], abs=1e-12)


# --- property tests: random full-rank Swedish layouts ----------------------------------------------
wheel_st = st.tuples(
    st.floats(-0.5, 0.5),
    st.floats(-0.5, 0.5),  # position
    st.floats(-math.pi, math.pi),  # drive direction
    st.floats(-60, 60),  # roller angle [deg]
    st.floats(0.02, 0.2),  # radius
)


def swedish_robot(specs, rotate=0.0):
    c, s = math.cos(rotate), math.sin(rotate)
    wheels = tuple(
        Wheel(f"w{i}", "swedish", c * x - s * y, s * x + c * y, d + rotate, r, math.radians(g))
        for i, (x, y, d, g, r) in enumerate(specs)
    )
    return Robot("random", wheels)


@given(st.lists(wheel_st, min_size=3, max_size=6), st.tuples(*[st.floats(-2, 2)] * 3))
def test_ik_fk_round_trip(specs, twist):
    try:
        robot = swedish_robot(specs)
    except SingularLayoutError:
        assume(False)
    assume(np.linalg.cond(robot.ik_matrix) < 1e6)
    w = robot.ik(twist).wheel_speeds
    fk = robot.fk(w)
    np.testing.assert_allclose(fk.twist, twist, atol=1e-7 * (1 + np.linalg.cond(robot.ik_matrix)))
    assert fk.residual_norm < 1e-6


@given(st.lists(wheel_st, min_size=3, max_size=5), st.floats(-math.pi, math.pi), st.tuples(*[st.floats(-2, 2)] * 3))
def test_rotating_the_layout_rotates_the_twist(specs, alpha, twist):
    """Rotating every wheel (position and direction) by alpha about the origin is the same robot
    seen in a rotated body frame: wheel speeds for the rotated twist are unchanged."""
    try:
        a, b = swedish_robot(specs), swedish_robot(specs, alpha)
    except SingularLayoutError:
        assume(False)
    c, s = math.cos(alpha), math.sin(alpha)
    rotated = [c * twist[0] - s * twist[1], s * twist[0] + c * twist[1], twist[2]]
    np.testing.assert_allclose(b.ik(rotated).wheel_speeds, a.ik(twist).wheel_speeds, atol=1e-9)
    assert b.mobility.condition_number == pytest.approx(a.mobility.condition_number, rel=1e-6)


def test_redundant_fk_residual_detects_slip():
    """omni4: the four speeds obey one compatibility condition; a slipping wheel violates it."""
    robot = load_robot("omni4")
    w = robot.ik([0.3, 0.1, 0.2]).wheel_speeds
    assert robot.fk(w).residual_norm < 1e-12
    slipped = w + np.array([0.5, 0, 0, 0])
    fk = robot.fk(slipped)
    # the residual is the projection of the slip onto the left null space of J: here (1,-1,1,-1)/2
    n = np.array([1, -1, 1, -1]) / 2.0
    np.testing.assert_allclose(fk.residual, n * (n @ [0.5, 0, 0, 0]), atol=1e-12)


def test_fk_stacks_broadcast(tomasi):
    twists = np.random.default_rng(1).normal(size=(5, 7, 3))
    w = tomasi.ik(twists).wheel_speeds
    assert w.shape == (5, 7, 3)
    np.testing.assert_allclose(tomasi.fk(w).twist, twists, atol=1e-12)


# --- constrained robots ----------------------------------------------------------------------------------
def test_diff_drive_refuses_sideways_twist():
    robot = load_robot("diff-drive")
    with pytest.raises(InfeasibleTwistError, match=r"fixed wheel 'left' would slide sideways at 0\.2 m/s"):
        robot.ik([1.0, 0.2, 0.0])
    res = robot.ik([1.0, 0.2, 0.0], on_infeasible="return")
    np.testing.assert_allclose(res.violation, [0.2, 0.2])
    assert not res.feasible
    with pytest.raises(OmnikinError, match="on_infeasible"):
        robot.ik([1, 0, 0], on_infeasible="ignore")


def test_diff_drive_fk_closed_form():
    """Burgard: V = (v_r + v_l)/2, omega = (v_r - v_l)/l with l = 0.33 m, r = 0.0825 m."""
    robot = load_robot("diff-drive")
    wl, wr = 7.0, 9.0
    fk = robot.fk([wl, wr])
    r, track = 0.0825, 0.33
    np.testing.assert_allclose(fk.twist, [(wr + wl) * r / 2, 0.0, (wr - wl) * r / track], atol=1e-12)


def test_ackermann_steering_closed_form():
    """ICR on the rear axle at distance R: tan(phi_i) = d / (R -+ b) for the left/right wheel."""
    robot = load_robot("ackermann")
    v, w = 1.0, 0.4
    R, d, b = v / w, 0.6, 0.25
    res = robot.ik([v, 0.0, w])
    np.testing.assert_allclose(res.steer_angles, [math.atan(d / (R - b)), math.atan(d / (R + b))], atol=1e-12)
    np.testing.assert_allclose(res.wheel_speeds[2], w * math.hypot(d, R - b) / 0.1, atol=1e-12)
    with pytest.raises(InfeasibleTwistError, match="steered outside its limits"):
        robot.ik([0.1, 0.0, 2.0])  # needs more than 35 deg


def test_synchro_translation_steers_all_wheels_alike():
    robot = load_robot("synchro")
    res = robot.ik([0.3, 0.4, 0.0])
    np.testing.assert_allclose(res.steer_angles, [math.atan2(0.4, 0.3)] * 3, atol=1e-12)
    np.testing.assert_allclose(res.wheel_speeds, [0.5 / 0.05] * 3, atol=1e-12)


def test_steer_hint_picks_reversed_branch():
    robot = load_robot("synchro")
    res = robot.ik([-0.3, 0.0, 0.0], steer_hint=[0.0, 0.0, 0.0])
    np.testing.assert_allclose(res.steer_angles, [0.0] * 3, atol=1e-12)  # drive backwards
    np.testing.assert_allclose(res.wheel_speeds, [-6.0] * 3, atol=1e-12)


def test_off_centred_steerable_needs_no_steering_rate():
    """XR4000: at the returned angles the swivel rate n.v_axis/d - omega vanishes (steady state)."""
    robot = load_robot("xr4000")
    twist = np.array([0.3, -0.2, 0.5])
    res = robot.ik(twist)
    for w, phi, speed in zip(robot.wheels, res.steer_angles, res.wheel_speeds, strict=True):
        delta = w.drive + phi
        v = np.array([twist[0] - twist[2] * w.y, twist[1] + twist[2] * w.x])
        n = np.array([-math.sin(delta), math.cos(delta)])
        u = np.array([math.cos(delta), math.sin(delta)])
        assert n @ v / w.offset - twist[2] == pytest.approx(0.0, abs=1e-12)
        # the contact, offset behind the axis, rolls at the wheel speed
        contact = np.array([w.x, w.y]) - w.offset * u
        vc = np.array([twist[0] - twist[2] * contact[1], twist[1] + twist[2] * contact[0]])
        assert u @ vc / w.radius == pytest.approx(speed, abs=1e-12)
        assert n @ vc == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("heading", [0.0, 90.0])
def test_off_centred_wheels_standing_parallel_still_give_the_motion(heading):
    """XR4000 driving straight: its four wheels stand parallel, so their rolling rows see no motion
    across them. Measured steering angles a fraction of a microradian apart (a physics run) and
    wheel speeds off by a tick's worth must not turn that blind direction into kilometres: the
    off-centred wheels' contacts do not slide sideways either (n . v_p = offset omega, steady)."""
    robot = load_robot("xr4000")
    twist = 0.3 * np.array([math.cos(math.radians(heading)), math.sin(math.radians(heading)), 0.0])
    ik = robot.ik(twist)
    steer = ik.steer_angles + np.array([1.2e-7, -0.4e-7, 0.9e-7, -1.2e-7])
    speeds = ik.wheel_speeds + np.array([1e-3, -1e-3, -1e-3, 1e-3])
    measured = robot.fk(speeds, steer).twist
    assert measured == pytest.approx(twist, abs=1e-3)  # the speeds' error: 5e-5 m/s at the rims


def test_steerable_fk_round_trip():
    for name in ("ackermann", "synchro", "xr4000", "villasenor-omni3"):
        robot = load_robot(name)
        twist = np.array([0.2, 0.0, 0.1]) if name == "ackermann" else np.array([0.2, 0.1, 0.15])
        res = robot.ik(twist)
        fk = robot.fk(res.wheel_speeds, res.steer_angles)
        np.testing.assert_allclose(fk.twist, twist, atol=1e-10, err_msg=name)


def test_fk_of_steerable_robot_without_angles_is_an_error():
    with pytest.raises(OmnikinError, match="steering angles"):
        load_robot("synchro").fk([1.0, 1.0, 1.0])


def test_wrong_wheel_count_is_named(tomasi):
    with pytest.raises(OmnikinError, match=r"wheel_speeds: expected shape \(\.\.\., 3\), got \(2,\)"):
        tomasi.fk([1.0, 2.0])
    with pytest.raises(OmnikinError, match="non-finite"):
        tomasi.ik([np.nan, 0, 0])


# --- constant matrices are built once and cannot be corrupted by a caller ------------------------------
def test_constant_matrices_are_read_only_and_match_fresh_ones():
    """Without steering the Jacobian and the FK operator are cached: writing into them must fail
    (a caller's in-place edit would otherwise change every later result), and the cached values
    must equal matrices built from the wheel rows and the pseudo-inverse directly."""
    robot = load_robot("omni4")
    jac = robot.jacobian()
    with pytest.raises(ValueError):
        jac[0, 0] = 1.0
    fresh = np.stack([w.rolling_row() for w in robot.rolling])
    np.testing.assert_array_equal(robot.jacobian(), fresh)
    subset = ["w1", "w2", "w3"]
    f = robot.fk_matrix(None, subset)
    with pytest.raises(ValueError):
        f[0, 0] = 1.0
    np.testing.assert_allclose(f, np.linalg.pinv(fresh[:3]), atol=1e-12)
    np.testing.assert_allclose(robot.fk_matrix(), np.linalg.pinv(fresh), atol=1e-12)
    # a subset's operator is not the whole robot's one
    assert robot.fk_matrix().shape == (3, 4) and f.shape == (3, 3)


def test_steered_jacobian_still_follows_the_steering():
    """Caching applies to fixed layouts only: a steerable robot's Jacobian changes with steer."""
    robot = load_robot("xr4000")
    zero = robot.jacobian(np.zeros(len(robot.steerable)))
    turned = robot.jacobian(np.full(len(robot.steerable), 0.5))
    assert not np.allclose(zero, turned)
    w = robot.steerable[0]
    np.testing.assert_allclose(turned[0], w.rolling_row(0.5), atol=1e-15)


# --- numeric sanity: finite input that overflows is refused, naming the argument --------------------------------
@pytest.mark.parametrize("twist", [[1e308, 0.0, 0.0], [0.0, -1e308, 0.0], [0.0, 0.0, 1.7e308]])
def test_ik_overflow_is_an_input_error_naming_the_twist(tomasi, twist):
    """Each wheel speed is a sum of twist components over r = 0.04125 m: 1e308 / r overflows."""
    with pytest.raises(InputError, match=r"^twist: \[.*\] is too large: the wheel speeds overflow"):
        tomasi.ik(twist)
    with pytest.raises(InputError, match="twist"):
        tomasi.wheel_speeds(twist)
    with pytest.raises(InputError, match="twist"):  # wheel 3's roller: (0.5 + 0.866) 1.5e308 m/s
        tomasi.roller_speeds([1.5e308, 1.5e308, 0.0])


def test_ik_overflow_in_a_stack_names_the_sample(tomasi):
    twists = np.zeros((5, 3))
    twists[3] = [0.0, 1e308, 0.0]
    with pytest.raises(InputError, match=r"^twist at index \(3,\): \[0.0, 1e\+308, 0.0\] is too large"):
        tomasi.ik(twists)


def test_world_frame_overflow_names_the_velocity(tomasi):
    """At heading 45 deg, vx = xdot cos + ydot sin: two 1.5e308 add up to more than the largest double."""
    with pytest.raises(InputError, match="^velocity: .* is too large: the body twist overflow"):
        tomasi.ik([1.5e308, 1.5e308, 0.0], heading=math.pi / 4)


def test_fk_overflow_is_an_input_error_naming_the_wheel_speeds():
    """Three omni wheels of radius 10 m on a 0.1 m circle: all turning at 1e308 rad/s means spinning at
    omega = r w / l = 1e310 rad/s, not representable."""
    robot = omni_robot([0, 120, 240], distance=0.1, radius=10.0)
    with pytest.raises(InputError, match="^wheel_speeds: .* is too large: the twist overflow"):
        robot.fk([1e308, 1e308, 1e308])
    assert np.all(np.isfinite(robot.fk([1e300, 1e300, 1e300]).twist))  # large but representable: fine


def test_cli_ik_of_a_huge_twist_is_one_line_error(capsys):
    from omnikin.cli.main import main

    assert main(["ik", "tomasi-omni3", "1e308", "0", "0"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.startswith("omnikin: error: twist: [1e+308, 0.0, 0.0] is too large")
    assert len(err.strip().splitlines()) == 1 and "nan" not in err and "inf" not in err


@pytest.mark.parametrize(
    "ticks, gear",
    [
        (1e-310, 1.0),
        (1e-200, 1.0),
        (0.5, 1.0),
        (2.0**32 + 1, 1.0),
        (600, 1e-310),
        (600, 1e-200),
        (600, 1e300),
        (600, 0.0),
    ],
)
def test_encoder_outside_physical_ranges_is_refused(ticks, gear):
    """1e-310 ticks per turn made 2 pi / (ticks gear) infinite (NaN poses); 1e-200 a ZeroDivisionError."""
    with pytest.raises(InputError, match="must lie in"):
        Encoder(ticks, gear)


@pytest.mark.parametrize("ticks, gear", [(1, 1e-3), (2.0**32, 1e4), (600, 1.0), (4096.5, 19.7)])
def test_encoder_within_ranges_gives_a_finite_angle_per_tick(ticks, gear):
    step = Encoder(ticks, gear).rad_per_tick
    assert step == pytest.approx(2 * math.pi / (ticks * gear)) and math.isfinite(step) and step > 0


@pytest.mark.parametrize(
    "kw",
    [
        {"radius": 20.0},
        {"radius": 5e-5},
        {"x": 1e4},
        {"y": -2e3},
        {"roller": math.radians(85)},
        {"max_speed": 1e5},
        {"max_speed": -1.0},
        {"encoder": 600},
        {"steer": "big"},
    ],
)
def test_wheel_outside_physical_ranges_is_refused(kw):
    args = {"name": "a", "type": "swedish", "x": 0.1, "y": 0.0, "drive": math.pi / 2, "radius": 0.05}
    args.update(kw)
    with pytest.raises(InputError):
        Wheel(**args)


@pytest.mark.parametrize(
    "kw", [{"offset": 11.0}, {"offset": -0.1}, {"lower": -4.0}, {"upper": 4.0}, {"lower": 0.5, "upper": 0.5}]
)
def test_steer_outside_ranges_is_refused(kw):
    with pytest.raises(InputError):
        Steer(**kw)


# --- validation is linear in the number of wheels ---------------------------------------------------------------
def test_robot_validation_and_wheel_lookups_are_linear():
    """20 000 wheels: the duplicate-name check counted every name in the whole list (names.count) and
    each wheel look-up scanned the list, about n^2 / 2 name comparisons. Counted, not timed: linear
    work makes a few per wheel."""
    import dataclasses

    n = 20_000
    wheels = tuple(dataclasses.replace(w, name=CountedName(w.name)) for w in circle_wheels(n))
    CountedName.counts, CountedName.budget = [], 10 * n
    robot = Robot("many", wheels)
    robot.check_observable(robot.encoded_names)
    assert robot.wheel(wheels[-1].name) is wheels[-1]
    assert robot.wheel(str(wheels[n // 2].name)) is wheels[n // 2]
    assert len(CountedName.counts) < 10 * n, len(CountedName.counts)


def test_duplicate_among_many_wheels_is_found_and_named():
    wheels = list(circle_wheels(20_000))
    wheels[-1] = Wheel("w7", "omni", 0.3, 0.0, math.pi / 2, 0.05)
    with pytest.raises(InputError, match=r"duplicate wheel name 'w7' \(also wheel #8\)$"):
        Robot("many", tuple(wheels))
