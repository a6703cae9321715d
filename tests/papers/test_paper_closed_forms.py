"""omnikin's presets against the (corrected) closed forms of the seed papers.

Companion of ``tests/papers/test_errata.py`` and ``docs/errata.md`` (entry ids in the test names).
Every expected value is produced here by a SymPy derivation from first principles -- the
rigid-body velocity of the wheel hub, and the 3-D no-slip condition at the wheel / roller
contact -- which is first checked to reproduce the paper's (corrected) closed form and then
evaluated numerically and compared with omnikin. No expected value comes from omnikin.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import sympy as sp
from sympy import cos, pi, sin, sqrt

from omnikin import Wheel, load_robot
from omnikin.kinematics.se2 import compose, exp
from omnikin.odometry.integration import integrate

t = sp.Symbol("t", real=True)
vx, vy, w = sp.symbols("v_x v_y omega", real=True)
TWIST = sp.Matrix([vx, vy, w])
ZHAT = sp.Matrix([0, 0, 1])
RNG = np.random.default_rng(20240611)


def rot2(a):
    return sp.Matrix([[cos(a), -sin(a)], [sin(a), cos(a)]])


@lru_cache(None)
def _bpv_general():
    px, py = sp.symbols("p_x p_y", real=True)
    X, Y, TH = (sp.Function(n)(t) for n in ("X", "Y", "Theta"))
    world = sp.Matrix([X, Y]) + rot2(TH) * sp.Matrix([px, py])
    rates = rot2(TH) * sp.Matrix([vx, vy])
    v = (rot2(TH).T * world.diff(t)).subs({X.diff(t): rates[0], Y.diff(t): rates[1], TH.diff(t): w})
    v = v.applyfunc(lambda e: sp.simplify(sp.expand(e)))
    assert not v.has(TH), v  # the heading drops out
    return v, px, py


def body_point_velocity(p):
    """Velocity [body axes] of body point ``p`` for the twist, by differentiating its world position."""
    v, px, py = _bpv_general()
    return v.subs({px: p[0], py: p[1]})


def swedish_no_slip(v_hub, delta, gamma, R, rho):
    """Wheel spin (right-handed about the axle (-sin delta, cos delta, 0), i.e. driving the hub
    along u = (cos delta, sin delta)) and roller spin (right-handed about the roller axis at
    delta + gamma) that keep the contact point of the roller at rest."""
    ww, wr = sp.symbols("w_w w_r", real=True)
    a = sp.Matrix([-sin(delta), cos(delta), 0])
    e = sp.Matrix([cos(delta + gamma), sin(delta + gamma), 0])
    hub = sp.Matrix([v_hub[0], v_hub[1], 0])
    c = hub + (ww * a).cross(-(R - rho) * ZHAT) + (ww * a + wr * e).cross(-rho * ZHAT)
    sol = sp.solve([c[0], c[1]], [ww, wr], dict=True)[0]
    return sol[ww], sol[wr]


def assert_close(actual, expected, atol=1e-10):
    np.testing.assert_allclose(np.asarray(actual, float), np.asarray(expected, float), rtol=1e-9, atol=atol)


def twists(n=6):
    return RNG.uniform(-1.0, 1.0, size=(n, 3))


# ----------------------------------------------------------------------------- reference row


def test_reference_swedish_rolling_and_roller_rows():
    """omnikin's Wheel.rolling_row / roller_row (conventions.md) against the 3-D no-slip."""
    d, g, x, y = sp.symbols("delta gamma x y", real=True)
    R, rho = sp.symbols("R rho", positive=True)
    vp = body_point_velocity((x, y))
    ww, wr = swedish_no_slip(vp, d, g, R, rho)
    # the hub velocity left after the drive term is the roller term s * n, s = -rho * wr
    u = sp.Matrix([cos(d), sin(d)])
    n = sp.Matrix([-sin(d + g), cos(d + g)])
    s = -rho * wr
    assert sp.simplify(sp.expand_trig(vp - R * ww * u - s * n)) == sp.zeros(2, 1)
    row_w = sp.lambdify((d, g, x, y, R), sp.Matrix([ww]).jacobian(TWIST), "numpy")
    row_s = sp.lambdify((d, g, x, y, R, rho), sp.Matrix([s]).jacobian(TWIST), "numpy")
    for _ in range(12):
        dv, xv, yv = RNG.uniform(-np.pi, np.pi), RNG.uniform(-1, 1), RNG.uniform(-1, 1)
        gv = RNG.choice([0.0, np.pi / 4, -np.pi / 4, RNG.uniform(-1.2, 1.2)])
        Rv = RNG.uniform(0.02, 0.2)
        wheel = Wheel("w", "swedish", xv, yv, dv, Rv, roller=gv)
        assert_close(wheel.rolling_row(), np.ravel(row_w(dv, gv, xv, yv, Rv)))
        assert_close(wheel.roller_row(), np.ravel(row_s(dv, gv, xv, yv, Rv, 0.01)))


# ----------------------------------------------------------------------------- Garcia-Sillas

RR_, LL, rr_ = sp.symbols("R L r", positive=True)
S3 = sqrt(3)
G_LAMBDA = [(-LL, 0), (LL / 2, LL * S3 / 2), (LL / 2, -LL * S3 / 2)]
G_THETA = [pi, pi / 3, -pi / 3]  # theta_i = alpha_i (+ gamma_i = 0, see errata G11)
G_NUM = {RR_: 0.05, LL: 0.15, rr_: 0.0125}


@lru_cache(None)
def garcia_derived():
    """Per wheel: wheel spin about +x_i and roller spin about +y_i (frame R_i at theta_i) from
    the 3-D no-slip. In omnikin's terms the drive is -y_i (delta = theta - 90 deg), the roller
    axis is -y_i too (gamma = 0), and the paper's roller spin about +y_i is -wr."""
    rows_w, rows_r = [], []
    for lam, th in zip(G_LAMBDA, G_THETA, strict=True):
        ww, wr = swedish_no_slip(body_point_velocity(lam), th - pi / 2, 0, RR_, rr_)
        rows_w.append(sp.simplify(ww))
        rows_r.append(sp.simplify(-wr))
    return sp.Matrix(rows_w).jacobian(TWIST).applyfunc(sp.simplify), sp.Matrix(rows_r)


def test_G24_garcia_preset_ik_matrix_is_eq30():
    J, _ = garcia_derived()
    eq30 = sp.Matrix(
        [
            [0, 1 / RR_, -LL / RR_],
            [S3 / (2 * RR_), -1 / (2 * RR_), -LL / RR_],
            [-S3 / (2 * RR_), -1 / (2 * RR_), -LL / RR_],
        ]
    )
    assert sp.simplify(J - eq30) == sp.zeros(3, 3)
    robot = load_robot("garcia-sillas-omni3")
    assert_close(robot.ik_matrix, np.array(J.subs(G_NUM), dtype=float))
    for tw in twists():
        assert_close(robot.ik(tw).wheel_speeds, np.array((J * sp.Matrix(tw)).subs(G_NUM), dtype=float).ravel())


def test_G23_garcia_preset_fk_matrix_is_corrected_eq29():
    J, _ = garcia_derived()
    F = J.inv().applyfunc(sp.simplify)
    eq29_corrected = sp.Matrix([[0, RR_ / S3, -RR_ / S3], [2 * RR_ / 3, -RR_ / 3, -RR_ / 3], [-RR_ / (3 * LL)] * 3])
    assert sp.simplify(F - eq29_corrected) == sp.zeros(3, 3)
    robot = load_robot("garcia-sillas-omni3")
    assert_close(robot.fk_matrix(), np.array(F.subs(G_NUM), dtype=float))
    printed = eq29_corrected.copy()
    printed[0, 2] = RR_ / S3
    assert not np.allclose(robot.fk_matrix(), np.array(printed.subs(G_NUM), dtype=float))


def test_G17_garcia_roller_speeds_eq20_22():
    """omnikin's roller_speeds / r equal eq 20-22 with the paper's sign (roller spin about +y_i,
    i.e. roller surface speed positive along x_i = omnikin's n = (-sin delta, cos delta))."""
    J, wr_rows = garcia_derived()
    wx = J * TWIST  # wheel speeds of the twist
    printed = sp.Matrix(
        [RR_ * (wx[2] - wx[1]) / (rr_ * S3), RR_ * (wx[0] - wx[2]) / (rr_ * S3), RR_ * (wx[1] - wx[0]) / (rr_ * S3)]
    )
    assert sp.simplify(printed - wr_rows) == sp.zeros(3, 1)
    robot = load_robot("garcia-sillas-omni3")
    f = sp.lambdify((vx, vy, w), wr_rows.subs(G_NUM), "numpy")
    for tw in twists():
        assert_close(robot.roller_speeds(tw) / 0.0125, np.ravel(f(*tw)))


# ----------------------------------------------------------------------------- Tomasi & Todt

T_R, T_L = 0.04125, 0.113
li, r_, th, al, be = sp.symbols("l_i r theta_i alpha_i beta_i", real=True)


@lru_cache(None)
def tomasi_wheel():
    """(omega_i, V_ir) from the hub velocity and the wheel model of Fig. 5 (drive along y',
    roller along (sin a, cos a) in (x', y')), for alpha = 90 deg."""
    wi, Vir = sp.symbols("omega_i V_ir", real=True)
    vp = body_point_velocity((li * cos(be), li * sin(be)))
    ex, ey = sp.Matrix([cos(th), sin(th)]), sp.Matrix([-sin(th), cos(th)])
    sol = sp.solve(list(Vir * ex + wi * r_ * ey - vp), [wi, Vir], dict=True)[0]
    return sp.simplify(sol[wi]), sp.simplify(sol[Vir])


def _tomasi_E_row(theta, beta, alpha=pi / 2):
    g = theta - alpha
    return sp.Matrix([[cos(g), sin(g), li * sin(g - beta)]]) / sin(alpha)


def test_T13_tomasi_preset_is_eq21_with_the_sign_corrected():
    wi, _ = tomasi_wheel()
    robot = load_robot("tomasi-omni3")
    betas = [0, 2 * pi / 3, 4 * pi / 3]
    num = {li: T_L, r_: T_R}
    corrected, printed_flipped = [], []
    for b in betas:
        derived = wi.subs({th: b, be: b})  # omnikin default: u = CCW tangent  <=>  theta_i = beta_i
        row_c = -(_tomasi_E_row(b, b) * TWIST)[0] / r_  # corrected eq 21
        assert sp.simplify(sp.expand_trig(row_c - derived)) == 0
        row_p = (_tomasi_E_row(b, b) * TWIST)[0] / r_  # printed eq 21 ...
        assert sp.simplify(sp.expand_trig(row_p + derived)) == 0  # ... is its negative
        # printed eq 21 holds only with the wheel frames turned by 180 deg (theta_i = beta_i + pi)
        row_p_flip = (_tomasi_E_row(b + pi, b) * TWIST)[0] / r_
        assert sp.simplify(sp.expand_trig(row_p_flip - derived)) == 0
        corrected.append(sp.Matrix([row_c]).jacobian(TWIST).subs(num))
        printed_flipped.append(sp.Matrix([row_p_flip]).jacobian(TWIST).subs(num))
    assert_close(robot.ik_matrix, np.array(sp.Matrix.vstack(*corrected), dtype=float))
    assert_close(robot.ik_matrix, np.array(sp.Matrix.vstack(*printed_flipped), dtype=float))
    # eq 22: v = -E twist = r * omega
    E = sp.Matrix.vstack(*[_tomasi_E_row(b, b) for b in betas]).subs(num)
    for tw in twists():
        assert_close(T_R * robot.ik(tw).wheel_speeds, -np.array(E * sp.Matrix(tw), dtype=float).ravel())


def test_T12_tomasi_preset_roller_speed_is_minus_V_ir():
    """omnikin's roller speed is positive along n = drive rotated by +90 deg (inwards for the
    CCW-tangent drive); Tomasi's V_ir is positive along x' (outwards): s = -V_ir."""
    _, Vir = tomasi_wheel()
    robot = load_robot("tomasi-omni3")
    row2 = (sp.Matrix([[cos(th), sin(th), li * sin(th - be)]]) * TWIST)[0]  # corrected eq 20, row 2, alpha = 90
    assert sp.simplify(sp.expand_trig(row2 - Vir)) == 0
    betas = (0, 2 * np.pi / 3, 4 * np.pi / 3)
    f = sp.lambdify((vx, vy, w), [-row2.subs({th: b, be: b, li: T_L}) for b in betas])
    for tw in twists():
        assert_close(robot.roller_speeds(tw), f(*tw))


def test_T16_tomasi_preset_world_rate_ik_is_eq24():
    robot = load_robot("tomasi-omni3")
    thc = sp.Symbol("theta_c", real=True)
    H = sp.Matrix([[cos(thc), -sin(thc), 0], [sin(thc), cos(thc), 0], [0, 0, 1]])
    E = sp.Matrix.vstack(*[_tomasi_E_row(b, b) for b in (0, 2 * pi / 3, 4 * pi / 3)]).subs({li: T_L})
    for rates in twists(4):
        heading = RNG.uniform(-np.pi, np.pi)
        v = -(E * H.inv() * sp.Matrix(rates)).subs(thc, heading)  # eq 24 [m/s]
        assert_close(robot.ik(rates, heading=heading).wheel_speeds, np.array(v, dtype=float).ravel() / T_R)


# ----------------------------------------------------------------------------- Burgard


def _dd_derivation():
    V, om, ll, vl, vr = sp.symbols("V omega l v_l v_r", real=True)
    sub = {vx: V, vy: 0, w: om}
    left = body_point_velocity((0, ll / 2)).subs(sub)[0]
    right = body_point_velocity((0, -ll / 2)).subs(sub)[0]
    sol = sp.solve([left - vl, right - vr], [V, om], dict=True)[0]
    assert sp.simplify(sol[om] - (vr - vl) / ll) == 0 and sp.simplify(sol[V] - (vr + vl) / 2) == 0
    return sp.lambdify((vl, vr, ll), [sol[V], sol[om]]), sp.lambdify((V, om, ll), [left, right])


def test_B03_diff_drive_preset_matches_burgard():
    fk_f, ik_f = _dd_derivation()
    robot = load_robot("diff-drive")
    ll, r = 0.33, 0.0825
    assert robot.rolling_names == ["left", "right"]
    for v_l, v_r in RNG.uniform(-1, 1, size=(6, 2)):
        V, om = fk_f(v_l, v_r, ll)
        res = robot.fk([v_l / r, v_r / r])
        assert_close(res.twist, [V, 0.0, om])
        assert_close(res.residual, [0.0, 0.0])
        assert_close(robot.ik([V, 0.0, om]).wheel_speeds, np.array(ik_f(V, om, ll)) / r)
    assert robot.mobility.campion_type == (2, 0) and not robot.mobility.holonomic


def test_B05_rotation_about_icc_matches_exact_integration():
    x, y, th0, V, om, dt = sp.symbols("x y theta V omega delta_t", real=True)
    Rs = V / om
    icc = sp.Matrix([x - Rs * sin(th0), y + Rs * cos(th0)])
    M = sp.Matrix([[cos(om * dt), -sin(om * dt), 0], [sin(om * dt), cos(om * dt), 0], [0, 0, 1]])
    burgard = M * sp.Matrix([x - icc[0], y - icc[1], th0]) + sp.Matrix([icc[0], icc[1], om * dt])
    f = sp.lambdify((x, y, th0, V, om, dt), burgard, "numpy")
    for _ in range(6):
        pose = np.array([RNG.uniform(-2, 2), RNG.uniform(-2, 2), RNG.uniform(-3, 3)])
        Vv, omv, dtv = RNG.uniform(-1, 1), RNG.uniform(0.2, 2) * RNG.choice([-1, 1]), RNG.uniform(0.05, 1.5)
        expected = np.ravel(f(*pose, Vv, omv, dtv))
        expected[2] = (expected[2] + np.pi) % (2 * np.pi) - np.pi
        inc = np.array([[Vv * dtv, 0.0, omv * dtv]])
        assert_close(integrate(inc, start=pose, method="exact")[-1], expected, atol=1e-9)
        assert_close(compose(pose, exp(inc[0])), expected, atol=1e-9)


def test_B07_ackermann_preset_steering_matches_R_d_over_tan_phi():
    robot = load_robot("ackermann")
    d, h, r = 0.6, 0.25, 0.1
    R_, om, dd, hh = sp.symbols("R omega d h", real=True)
    sub = {vx: om * R_, vy: 0, w: om}
    phis, speeds = [], []
    for px, py in ((dd, hh), (dd, -hh)):
        v = body_point_velocity((px, py)).subs(sub)
        phis.append(sp.atan(sp.cancel(v[1] / v[0])))
        speeds.append(sqrt(v[0] ** 2 + v[1] ** 2))
    rear = [body_point_velocity((0, hh)).subs(sub)[0], body_point_velocity((0, -hh)).subs(sub)[0]]
    assert sp.simplify(sp.tan(phis[0]) - dd / (R_ - hh)) == 0
    assert sp.simplify(sp.tan(phis[1]) - dd / (R_ + hh)) == 0
    assert sp.simplify(rear[0] - om * (R_ - hh)) == 0 and sp.simplify(rear[1] - om * (R_ + hh)) == 0
    f_phi = sp.lambdify((R_, dd, hh), phis)
    f_spd = sp.lambdify((R_, om, dd, hh), rear + speeds)
    for Rv in (2.0, 3.5, -2.5, 10.0):
        omv = 0.4 if Rv > 0 else -0.4
        res = robot.ik([omv * Rv, 0.0, omv])
        assert_close(res.steer_angles, f_phi(Rv, d, h))
        # front wheels: the virtual middle wheel of the slide, R = d / tan(phi):
        # cot(phi_L) + cot(phi_R) = 2 R / d
        assert_close((1 / np.tan(res.steer_angles)).sum(), 2 * Rv / d)
        assert_close(res.wheel_speeds, np.array(f_spd(Rv, omv, d, h)) / r)  # forward motion, V > 0
    assert robot.mobility.degree_of_mobility == 1 and not robot.mobility.holonomic


def test_B08_synchro_preset_parallel_steering():
    robot = load_robot("synchro")
    for phi in (0.3, -1.2, 2.0):
        v = 0.4
        res = robot.ik([v * np.cos(phi), v * np.sin(phi), 0.0], steer_hint=[phi] * 3)
        drives = np.array([wh.drive for wh in robot.steerable])
        assert_close((res.steer_angles + drives - phi + np.pi) % (2 * np.pi) - np.pi, [0.0] * 3)
        assert_close(res.wheel_speeds, [v / 0.05] * 3)
    assert not robot.mobility.holonomic


@lru_cache(None)
def _mecanum_rim():
    a_, b_, R, rho = sp.symbols("a b R rho", positive=True)
    layout = {
        "front_left": (a_, b_, -pi / 4),
        "front_right": (a_, -b_, pi / 4),
        "rear_left": (-a_, b_, pi / 4),
        "rear_right": (-a_, -b_, -pi / 4),
    }
    rim = {}
    for name, (x, y, g) in layout.items():
        ww, _ = swedish_no_slip(body_point_velocity((x, y)), 0, g, R, rho)
        rim[name] = sp.expand(sp.simplify(R * ww))
    return rim, a_, b_


def test_B10_mecanum4_preset_matches_burgard_with_mapping():
    rim, a_, b_ = _mecanum_rim()
    robot = load_robot("mecanum4")
    a, b, r = 0.2355, 0.15, 0.0475
    order = ["rear_right", "rear_left", "front_left", "front_right"]  # Burgard's v0..v3
    # Burgard's relations inverted (with v_error = 0) -> v0..v3
    bx, by, bth = sp.symbols("vB_x vB_y vB_theta", real=True)
    v = sp.symbols("v0:4", real=True)
    rel = [
        (v[0] + v[1] + v[2] + v[3]) / 4 - by,
        (v[0] - v[1] + v[2] - v[3]) / 4 - bx,
        (v[0] - v[1] - v[2] + v[3]) / 4 - bth,
        (v[0] + v[1] - v[2] - v[3]) / 4,
    ]
    sol = sp.solve(rel, v, dict=True)[0]
    # these are the rim speeds of the twist (vx, vy, omega) = (vB_y, -vB_x, vB_theta / (a + b))
    tw = {vx: by, vy: -bx, w: bth / (a_ + b_)}
    for k, name in enumerate(order):
        assert sp.simplify(rim[name].subs(tw) - sol[v[k]]) == 0
    f = sp.lambdify((bx, by, bth), [sol[v[k]] for k in range(4)])
    for bxv, byv, bthv in twists():
        speeds = dict(zip(order, f(bxv, byv, bthv), strict=True))
        wheel = np.array([speeds[n] for n in robot.rolling_names]) / r
        res = robot.fk(wheel)
        assert_close(res.twist, [byv, -bxv, bthv / (a + b)])
        assert_close(res.residual, np.zeros(4), atol=1e-9)


def test_B10_mecanum4_fk_residual_is_burgard_v_error():
    rim, a_, b_ = _mecanum_rim()
    robot = load_robot("mecanum4")
    names = robot.rolling_names
    R = sp.Symbol("R", positive=True)
    J = (sp.Matrix([rim[n] for n in names]).jacobian(TWIST) / R).subs({a_: 0.2355, b_: 0.15, R: 0.0475})
    J = np.array(J, dtype=float)
    for omega in RNG.uniform(-10, 10, size=(6, 4)):
        s = dict(zip(names, omega * 0.0475, strict=True))
        v_error = (s["rear_right"] + s["rear_left"] - s["front_left"] - s["front_right"]) / 4
        res = robot.fk(omega)
        # least-squares residual: the part of omega orthogonal to range(J)
        proj = omega - J @ np.linalg.lstsq(J, omega, rcond=None)[0]
        assert_close(res.residual, proj, atol=1e-9)
        assert_close(res.residual, -(v_error / 0.0475) * np.array([1, 1, -1, -1]), atol=1e-9)


def test_B11_holonomy_matches_the_slides():
    for name in ("diff-drive", "ackermann", "synchro"):
        assert not load_robot(name).mobility.holonomic, name
    for name in ("mecanum4", "xr4000"):
        assert load_robot(name).mobility.holonomic, name


# ----------------------------------------------------------------------------- Villasenor


def test_V03_villasenor_preset_contact_points_are_eq6():
    robot = load_robot("villasenor-omni3")
    table = [  # alpha, beta [deg], delta, lambda [mm] (Table 1)
        (90, 45, (-223.66, -122.85), (-61.86, 56.72)),
        (270, 45, (99.71, -23.14), (-136.86, -73.19)),
        (270, 45, (24.75, 106.7), (13.14, -73.19)),
    ]
    a, b = sp.symbols("alpha beta", real=True)
    lam, dl = sp.Matrix(sp.symbols("l_x l_y", real=True)), sp.Matrix(sp.symbols("d_x d_y", real=True))
    p = lam + rot2(a + b) * dl  # eq 6
    f = sp.lambdify((a, b, *dl, *lam), p)
    for wheel, (adeg, bdeg, d, hip) in zip(robot.wheels, table, strict=True):
        expected = np.ravel(f(np.radians(adeg), np.radians(bdeg), *d, *hip)) / 1000.0
        assert_close(wheel.contact_point(), expected, atol=2e-5)  # preset rounded to 0.01 mm / 1e-3 deg
        assert abs(wheel.offset - np.hypot(*d) / 1000.0) < 1e-5
