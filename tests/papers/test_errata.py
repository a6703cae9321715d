"""Symbolic checks of every entry of ``docs/errata.md`` (the four source papers).

Each test carries the id of its errata entry: ``T..`` Tomasi & Todt, ``G..`` Garcia-Sillas
et al., ``V..`` Villasenor et al., ``B..`` Burgard & Krawez's slides.

The expected forms are derived here with SymPy from first principles, never copied from the
papers and never taken from omnikin:

* the velocity of a body point, by differentiating its world position
  ``X(t) + R(Theta(t)) p`` (:func:`body_point_velocity`);
* the no-slip condition at a wheel or roller contact, written as a 3-D rigid-body velocity
  (``v_hub + omega x (contact - centre) = 0``) with right-handed spins, z up;
* the Muir-Neuman frame chain ``C -> F_i -> D_i -> R_i`` of seeds 002/004, differentiated in
  time (:func:`mn_chain`).

A printed equation is either asserted identical to the derivation, or asserted to differ from
it -- the differing entries are listed exactly, evaluated at a generic numeric point -- and the
corrected form asserted identical. Trigonometric identities are decided exactly by reducing
polynomials in ``cos x, sin x`` modulo ``cos^2 x + sin^2 x - 1`` (:func:`trig_zero`).
"""

from __future__ import annotations

import itertools
from functools import lru_cache

import sympy as sp
from sympy import Rational as Q
from sympy import cos, pi, sin, sqrt
from sympy.core.function import AppliedUndef

# ----------------------------------------------------------------------------- helpers

t = sp.Symbol("t", real=True)
vx, vy, w = sp.symbols("v_x v_y omega", real=True)
TWIST = sp.Matrix([vx, vy, w])
XHAT, YHAT, ZHAT = sp.Matrix([1, 0, 0]), sp.Matrix([0, 1, 0]), sp.Matrix([0, 0, 1])
E90 = sp.Matrix([[0, -1], [1, 0]])  # z x (.) in the plane: rotation by +90 deg


def rot2(a):
    return sp.Matrix([[cos(a), -sin(a)], [sin(a), cos(a)]])


def se2(x, y, a):
    return sp.Matrix([[cos(a), -sin(a), x], [sin(a), cos(a), y], [0, 0, 1]])


def _trig_poly(e):
    """Numerator of ``e`` as a polynomial in (cos x, sin x) dummies, and the ideal."""
    e = sp.together(sp.expand_trig(sp.sympify(e)))
    num = sp.numer(e)
    args = sorted({a.args[0] for a in num.atoms(sp.sin, sp.cos)}, key=str)
    if any(not (x.is_Symbol or isinstance(x, AppliedUndef)) for x in args):
        raise ValueError(f"trig argument not a plain symbol after expansion: {args}")
    rep, back, gens, ideal = {}, {}, [], []
    for x in args:
        c, s = sp.Dummy(f"c_{x}"), sp.Dummy(f"s_{x}")
        rep[cos(x)], rep[sin(x)] = c, s
        back[c], back[s] = cos(x), sin(x)
        gens += [s, c]
        ideal.append(s**2 + c**2 - 1)
    return sp.expand(num.xreplace(rep)), gens, ideal, back, sp.denom(e)


def _reduce(p, gens, ideal):
    if p == 0 or not gens:
        return p
    others = sorted(p.free_symbols - set(gens), key=str)
    return sp.reduced(p, ideal, *gens, *others, order="lex")[1]


def trig_zero(e) -> bool:
    """Exact test of a trigonometric identity ``e == 0`` (plain-symbol angles)."""
    p, gens, ideal, _, _ = _trig_poly(e)
    rem = sp.expand(_reduce(p, gens, ideal))
    return rem == 0 or sp.simplify(rem) == 0


def trig_reduce(e):
    """``e`` with ``sin^2 -> 1 - cos^2`` reductions applied (numerator), as an expression."""
    p, gens, ideal, back, den = _trig_poly(e)
    return sp.expand(_reduce(p, gens, ideal)).xreplace(back) / den


def _mat(x):
    return x if isinstance(x, sp.MatrixBase) else sp.Matrix([x])


def same(a, b) -> bool:
    a, b = _mat(a), _mat(b)
    assert a.shape == b.shape, (a.shape, b.shape)
    return all(trig_zero(e) for e in (a - b))


_PRIMES = (3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71, 73, 79, 83)


def generic_point(*exprs):
    syms = sorted(set().union(*[_mat(e).free_symbols for e in exprs]), key=str)
    assert len(syms) <= len(_PRIMES)
    return {s: Q(p, 13) for s, p in zip(syms, _PRIMES[: len(syms)], strict=True)}


def wrong_entries(printed, derived):
    """1-based (row, col) of the entries where ``printed`` differs from ``derived``
    at a generic numeric point (so a listed entry is certainly wrong)."""
    a, b = _mat(printed), _mat(derived)
    assert a.shape == b.shape
    pt = generic_point(a, b)
    out = []
    for i in range(a.rows):
        for j in range(a.cols):
            if abs(complex(sp.N((a[i, j] - b[i, j]).xreplace(pt), 30))) > 1e-12:
                out.append((i + 1, j + 1))
    return out


def body_point_velocity(p):
    """Velocity [body axes] of the body point ``p`` for the body twist ``(vx, vy, omega)``,
    by differentiating its world position ``X + R(Theta) p`` and using the definition of the
    twist, ``(Xdot, Ydot) = R(Theta) (vx, vy)``, ``Thetadot = omega``."""
    X, Y, TH = (sp.Function(n)(t) for n in ("X", "Y", "Theta"))
    world = sp.Matrix([X, Y]) + rot2(TH) * sp.Matrix(p)
    rates = rot2(TH) * sp.Matrix([vx, vy])
    v = (rot2(TH).T * world.diff(t)).subs({X.diff(t): rates[0], Y.diff(t): rates[1], TH.diff(t): w})
    v = v.subs(TH, sp.Symbol("Theta", real=True))  # the heading must drop out
    return v.applyfunc(lambda e: sp.simplify(trig_reduce(e)))


def contact_velocity(v_hub_xy, spins):
    """Velocity of the material point at the floor contact: ``v_hub + sum omega_k x d_k``,
    ``spins`` = [(angular velocity 3-vector, vector from its centre to the contact)]."""
    v = sp.Matrix([v_hub_xy[0], v_hub_xy[1], 0])
    for omega_vec, d in spins:
        v += omega_vec.cross(d)
    return v


def swedish_no_slip(v_hub, delta, gamma, R, rho):
    """Wheel spin ``ww`` (right-handed about the axle ``a = (-sin delta, cos delta, 0)``, so
    that it drives the hub along ``u = (cos delta, sin delta)``) and roller spin ``wr``
    (right-handed about the roller axis ``e`` at ``delta + gamma``) that make the roller point
    at the contact stand still. Wheel radius ``R``, roller radius ``rho``."""
    ww, wr = sp.symbols("w_w w_r", real=True)
    a = sp.Matrix([-sin(delta), cos(delta), 0])
    e = sp.Matrix([cos(delta + gamma), sin(delta + gamma), 0])
    # roller centre at -(R - rho) z from the hub, contact at -rho z from the roller centre
    c = contact_velocity(v_hub, [(ww * a, -(R - rho) * ZHAT), (ww * a + wr * e, -rho * ZHAT)])
    sol = sp.solve([c[0], c[1]], [ww, wr], dict=True)[0]
    return sol[ww], sol[wr]


# ====================================================================================
# Tomasi & Todt (seed 000)
# ====================================================================================

al, th, be = sp.symbols("alpha_i theta_i beta_i", real=True)
li, r = sp.symbols("l_i r", positive=True)
w_i, V_ir = sp.symbols("omega_i V_ir", real=True)


@lru_cache(None)
def tomasi_truth():
    """(omega_i, V_ir) for a twist: rigid-body hub velocity equated to the wheel model of
    Fig. 5 (drive r*omega_i along y', roller speed V_ir along (sin a, cos a) in (x', y'),
    frame (x', y') at theta_i in the body), solved by SymPy."""
    vp = body_point_velocity((li * cos(be), li * sin(be)))
    local = sp.Matrix([sin(al) * V_ir, cos(al) * V_ir + w_i * r])
    ex, ey = sp.Matrix([cos(th), sin(th)]), sp.Matrix([-sin(th), cos(th)])  # x', y' in body axes
    sol = sp.solve(list(local[0] * ex + local[1] * ey - vp), [w_i, V_ir], dict=True)[0]
    return sp.Matrix([sol[w_i], sol[V_ir]])


def _umbmark_runs(n=5):
    cx, cy = sp.symbols("c_x c_y", real=True)
    nux = list(sp.symbols(f"nu_x1:{n}", real=True))
    nuy = list(sp.symbols(f"nu_y1:{n}", real=True))
    nux.append(-sum(nux))  # non-systematic part: zero mean over the n runs
    nuy.append(-sum(nuy))
    xc = sp.symbols(f"x_calc1:{n + 1}", real=True)
    yc = sp.symbols(f"y_calc1:{n + 1}", real=True)
    xa = [xc[i] + cx + nux[i] for i in range(n)]  # true stop = odometry stop + error
    ya = [yc[i] + cy + nuy[i] for i in range(n)]
    return cx, cy, xa, ya, xc, yc


def test_T01_umbmark_eq1_2_return_error():
    cx, cy, xa, ya, xc, yc = _umbmark_runs()
    eX = [xa[i] - xc[i] for i in range(5)]  # eq 1 as printed
    eY = [ya[i] - yc[i] for i in range(5)]  # eq 2
    # eq 1-2 return the error of the stop pose (true minus odometry), sign included
    assert sp.simplify(sum(eX) / 5 - cx) == 0 and sp.simplify(sum(eY) / 5 - cy) == 0
    assert sp.simplify(sum(xc[i] - xa[i] for i in range(5)) / 5 - cx) != 0  # the reverse sign is not


def test_T02_umbmark_eq3_4_centre_of_gravity():
    cx, cy, xa, ya, xc, yc = _umbmark_runs()
    n = 5
    mX = sp.Rational(1, n) * sum(xa[i] - xc[i] for i in range(n))  # eq 3 as printed
    mY = sp.Rational(1, n) * sum(ya[i] - yc[i] for i in range(n))  # eq 4
    # the mean removes the zero-mean non-systematic part and keeps the systematic error
    assert sp.expand(mX - cx) == 0 and sp.expand(mY - cy) == 0
    assert sp.expand(sum(xa[i] - xc[i] for i in range(n)) - cx) != 0  # without 1/n it would not


def test_T03_umbmark_eq5_6_euclidean_distance():
    mx, my, phi = sp.symbols("mX mY phi", real=True)
    euc = sqrt(mx**2 + my**2)  # eq 5-6 as printed (= Borenstein's r_c.g.)
    rotated = rot2(phi) * sp.Matrix([mx, my])
    # the distance of the centre of gravity from the target does not depend on the axes chosen
    assert sp.simplify(sqrt(rotated[0] ** 2 + rotated[1] ** 2) - euc) == 0
    assert sp.simplify(euc.subs({mx: 3, my: -4}) - 5) == 0


def test_T04_eq7_8_13_14_polar_placement():
    lx, ly = li * cos(be), li * sin(be)  # eq 7-8 = eq 13-14 as printed
    hub = rot2(be) * sp.Matrix([li, 0])  # the point at distance l_i along the ray at beta_i
    assert same(sp.Matrix([lx, ly]), hub)
    assert sp.simplify(sqrt(lx**2 + ly**2) - li) == 0


def test_T05_eq9_V_ir_is_not_the_rim_speed():
    truth = tomasi_truth().subs(al, pi / 2)
    vp = body_point_velocity((li * cos(be), li * sin(be)))
    ex, ey = sp.Matrix([cos(th), sin(th)]), sp.Matrix([-sin(th), cos(th)])
    omega_i_sol, V_ir_sol = truth
    # eq 9 as printed: V_ir = omega_i r -- false for the roller speed of eq 10
    assert wrong_entries(V_ir_sol, r * omega_i_sol) == [(1, 1)]
    # footnote: "alpha = 90 deg, so V_ir = 0" -- false, V_ir is the hub speed along x'
    assert wrong_entries(V_ir_sol, 0) == [(1, 1)]
    assert same(V_ir_sol, (ex.T * vp)[0])
    # corrected: omega_i r is the rim (drive) speed, the hub speed along y'
    assert same(r * omega_i_sol, (ey.T * vp)[0])


def test_T06_eq10_Ki1_roller_convention():
    """Eq 10 is the 3-D no-slip condition of a Swedish wheel with the mapping
    delta = theta + 90 deg, gamma = 90 deg - alpha (omnikin), V_ir = rho * omega_roller."""
    rho, R = sp.symbols("rho R", positive=True)
    vh = sp.symbols("v_hx v_hy", real=True)  # hub velocity, body axes
    delta, gamma = th + pi / 2, pi / 2 - al
    ww, wr = swedish_no_slip(vh, delta, gamma, R, rho)
    Ki1 = sp.Matrix([[0, sin(al)], [R, cos(al)]])  # eq 10 with wheel radius R
    local = rot2(th).T * sp.Matrix(vh)  # (V'_ix, V'_iy)
    assert same(Ki1 * sp.Matrix([ww, rho * wr]), local)
    # ... and the same no-slip gives omnikin's rolling row (conventions.md)
    a = delta + gamma
    row = (cos(a) * vh[0] + sin(a) * vh[1]) / (R * cos(gamma))
    assert same(ww, row)
    # without the mapping (alpha read as omnikin's gamma) eq 10 does not hold
    ww2, wr2 = swedish_no_slip(vh, delta, al, R, rho)
    assert wrong_entries(Ki1 * sp.Matrix([ww2, rho * wr2]), local) != []


def test_T07_eq11_12_Ki2_rotation():
    Ki2 = sp.Matrix([[cos(th), -sin(th)], [sin(th), cos(th)]])  # as printed
    ex, ey = sp.Matrix([cos(th), sin(th)]), sp.Matrix([-sin(th), cos(th)])  # x', y' in body axes
    a, b = sp.symbols("a b", real=True)
    assert same(Ki2 * sp.Matrix([a, b]), a * ex + b * ey)


def test_T08_eq15_Ki3_rigid_body():
    lx, ly = sp.symbols("l_ix l_iy", real=True)
    Ki3 = sp.Matrix([[1, 0, -ly], [0, 1, lx]])  # as printed
    assert same(Ki3 * TWIST, body_point_velocity((lx, ly)))


def _Ki():
    Ki1 = sp.Matrix([[0, sin(al)], [r, cos(al)]])
    Ki2 = rot2(th)
    Ki3 = sp.Matrix([[1, 0, -li * sin(be)], [0, 1, li * cos(be)]])
    return Ki1, Ki2, Ki3


def test_T09_eq16_17_solution():
    Ki1, Ki2, Ki3 = _Ki()
    assert trig_zero(Ki1.det() + r * sin(al))  # invertible iff sin(alpha) != 0
    sol = Ki1.inv() * Ki2.inv() * Ki3 * TWIST  # eq 17
    assert same(sol, tomasi_truth())


def test_T10_eq18_inverse_of_Ki1():
    Ki1, _, _ = _Ki()
    printed = sp.Matrix([[-cos(al) / (r * sin(al)), 1 / r], [1 / sin(al), 0]])
    assert same(printed * Ki1, sp.eye(2)) and same(Ki1 * printed, sp.eye(2))


def test_T11_eq19_inverse_of_Ki2():
    printed = sp.Matrix([[cos(th), sin(th)], [-sin(th), cos(th)]])
    assert same(printed * rot2(th), sp.eye(2))


def _tomasi_T(corrected: bool):
    g = th - al  # gamma_i = theta_i - alpha_i (Tomasi's gamma, not omnikin's)
    last = (-1 if corrected else 1) * r * li * sin(th - be)
    return sp.Matrix([[cos(g), sin(g), li * sin(g - be)], [-r * cos(th), -r * sin(th), last]])


def test_T12_eq20_T_matrix_entry_2_3():
    pref = 1 / (-r * sin(al))
    printed = pref * _tomasi_T(False) * TWIST
    assert wrong_entries(printed, tomasi_truth()) == [(2, 1)]  # the V_ir row
    assert wrong_entries(_tomasi_T(False), _tomasi_T(True)) == [(2, 3)]  # the single bad entry
    assert same(pref * _tomasi_T(True) * TWIST, tomasi_truth())


def _E_row():
    g = th - al
    return sp.Matrix([[cos(g) / sin(al), sin(g) / sin(al), li * sin(g - be) / sin(al)]])


def test_T13_eq21_missing_minus_sign():
    printed = (_E_row() * TWIST)[0] / r  # omega_i = (1/r_i) E_i twist
    truth = tomasi_truth()[0]
    assert wrong_entries(printed, truth) == [(1, 1)]
    assert same(-(_E_row() * TWIST)[0] / r, truth)  # corrected: omega = -diag(r)^-1 E twist


def test_T14_eq22_v_equals_minus_E():
    assert same(-(_E_row() * TWIST)[0], r * tomasi_truth()[0])


def _world_rates():
    """Body twist from world rates, derived: the body x axis is at theta_c in the world."""
    Xd, Yd, Td, thc = sp.symbols("Xdot_c Ydot_c omega_c theta_c", real=True)
    # world velocity of the body origin = R(theta_c) * (body-axis components)
    body = sp.Matrix(sp.symbols("b_x b_y", real=True))
    sol = sp.solve(list(rot2(thc) * body - sp.Matrix([Xd, Yd])), list(body), dict=True)[0]
    twist = sp.Matrix([sol[body[0]], sol[body[1]], Td])
    H = sp.Matrix([[cos(thc), -sin(thc), 0], [sin(thc), cos(thc), 0], [0, 0, 1]])
    return sp.Matrix([Xd, Yd, Td]), twist, H


def test_T15_eq23_H_inverse_direction():
    rates, twist, H = _world_rates()
    assert same(H.inv() * rates, twist)  # eq 23, with (X_c, Y_c, omega_c) read as world rates
    assert wrong_entries(H * rates, twist) == [(1, 1), (2, 1)]  # H the other way round is wrong


def test_T16_eq24_inverse_kinematics_in_world_rates():
    rates, twist, H = _world_rates()
    v_printed = -(_E_row() * H.inv() * rates)[0]  # eq 24, one wheel
    v_true = (r * tomasi_truth()[0]).subs({vx: twist[0], vy: twist[1], w: twist[2]})
    assert same(v_printed, v_true)


# ====================================================================================
# Muir-Neuman chain of Garcia-Sillas et al. (002) and Villasenor et al. (004)
# ====================================================================================

alp, gam, bet = sp.symbols("alpha gamma beta", real=True)
lamx, lamy, delx, dely = sp.symbols("lambda_x lambda_y delta_x delta_y", real=True)
bdot = sp.Symbol("betadot", real=True)
q_vx, q_vy, q_w = sp.symbols("v_ix v_iy omega_i", real=True)  # hat q_i = (v_ix, v_iy, omega_i, betadot)


@lru_cache(None)
def mn_chain():
    """Frames C -> F_i (at lambda, angle alpha) -> D_i (steering beta(t)) -> R_i (at delta,
    angle gamma). Returns p_i, the pose T_CR of R_i in C, and hat q_i = (v_ix, v_iy, omega_i,
    betadot) as functions of the body twist: velocity of the R_i origin (a point of the
    steering link) relative to the floor in R_i axes, and angular velocity of R_i."""
    X, Y, TH, BE = (sp.Function(n)(t) for n in ("X", "Y", "Theta", "beta"))
    Th = sp.Symbol("Theta", real=True)
    T_CR = se2(lamx, lamy, alp) * se2(0, 0, BE) * se2(delx, dely, gam)
    T_WR = se2(X, Y, TH) * T_CR
    thR = TH + alp + BE + gam
    rates = rot2(TH) * sp.Matrix([vx, vy])
    sub = {X.diff(t): rates[0], Y.diff(t): rates[1], TH.diff(t): w, BE.diff(t): bdot}
    v_i = (rot2(thR).T * T_WR[:2, 2].diff(t)).subs(sub)
    w_i_ = thR.diff(t).subs(sub)
    back = {TH: Th, BE: bet}
    q = sp.Matrix([v_i[0], v_i[1], w_i_, bdot]).subs(back).applyfunc(trig_reduce)
    assert not q.has(Th)  # body-frame quantities: the world heading drops out
    p = T_CR[:2, 2].subs(back)
    return p, T_CR.subs(back), q


@lru_cache(None)
def mn_jhat():
    """Derived wheel Jacobian hat J_i: V_c = hat J_i hat q_i (inverse of the chain map)."""
    _, _, q = mn_chain()
    A = q[:3, :].jacobian(TWIST)
    b = q[:3, :].diff(bdot)
    det = trig_reduce(A.det())
    assert sp.simplify(det - 1) == 0
    adj = A.adjugate().applyfunc(trig_reduce)
    return adj.row_join(-adj * b).applyfunc(trig_reduce)


def mn_printed_jhat():
    """Eq 5 of 002 (= eq 8 of 004) with eq 2-3 substituted."""
    thi = alp + bet + gam
    p = sp.Matrix([lamx, lamy]) + rot2(alp + bet) * sp.Matrix([delx, dely])
    return sp.Matrix([[cos(thi), -sin(thi), p[1], -lamy], [sin(thi), cos(thi), -p[0], lamx], [0, 0, 1, -1]]), p, thi


def conventional_qhat(r_):
    """hat q_i of a conventional wheel of radius r_ from 3-D no-slip: spin w_s right-handed
    about the axle +x_i (z up), rotational slip w_z, steering rate bd."""
    ws, wz, bd = sp.symbols("w_s w_z bd", real=True)
    v = sp.symbols("v_a v_b", real=True)
    c = contact_velocity(v, [(ws * XHAT, -r_ * ZHAT)])
    sol = sp.solve([c[0], c[1]], list(v), dict=True)[0]
    return sp.Matrix([sol[v[0]], sol[v[1]], wz, bd]), (ws, wz, bd)


def omni_qhat(R_, r_):
    """hat q_i of the omni wheel of 002 (radius R_, rollers of radius r_ at 90 deg): wheel spin
    w_x about +x_i, roller spin w_r about +y_i (the roller axis at the contact), slip w_z."""
    wx, wr, wz = sp.symbols("w_x w_r w_z", real=True)
    v = sp.symbols("v_a v_b", real=True)
    c = contact_velocity(v, [(wx * XHAT, -(R_ - r_) * ZHAT), (wx * XHAT + wr * YHAT, -r_ * ZHAT)])
    sol = sp.solve([c[0], c[1]], list(v), dict=True)[0]
    return sp.Matrix([sol[v[0]], sol[v[1]], wz, 0]), (wx, wr, wz)


def test_G01_eq1_velocity_composition():
    p, T_CR, q = mn_chain()
    thi = alp + bet + gam
    vi, wi_, lam = q[:2, :], q[2], sp.Matrix([lamx, lamy])
    printed = rot2(thi) * vi + wi_ * p + bdot * lam  # v_c = R(theta_i) v_i + omega_i p_i + betadot lambda_i
    assert wrong_entries(printed, sp.Matrix([vx, vy])) == [(1, 1), (2, 1)]
    corrected = rot2(thi) * vi - wi_ * E90 * p + bdot * E90 * lam
    assert same(corrected, sp.Matrix([vx, vy]))


def test_G02_eq2_3_contact_frame_pose():
    p, T_CR, _ = mn_chain()
    assert same(p, sp.Matrix([lamx, lamy]) + rot2(alp + bet) * sp.Matrix([delx, dely]))  # eq 2
    assert same(T_CR[:2, :2], rot2(alp + bet + gam))  # eq 3: theta_i = alpha + beta + gamma


def test_G03_eq4_sign_of_body_rate():
    _, _, q = mn_chain()
    wi_ = q[2]
    assert wrong_entries(bdot - wi_, w) == [(1, 1)]  # omega_c = betadot - omega_i: wrong sign
    assert same(wi_ - bdot, w)  # corrected, = third row of eq 5


def test_G04_eq5_wheel_jacobian_hat():
    J, _, _ = mn_printed_jhat()
    _, _, q = mn_chain()
    assert same(J, mn_jhat())
    assert same(J * q, TWIST)


def test_G05_eq6_7_conventional_wheel_matrix():
    rr = sp.Symbol("r_i", positive=True)
    qh, (ws, wz, bd) = conventional_qhat(rr)
    W6 = sp.Matrix([[0, 0], [-rr, 0], [0, 1], [0, 0]])
    W7 = sp.Matrix([[0, 0, 0], [-rr, 0, 0], [0, 1, 0], [0, 0, 1]])
    assert same(W6 * sp.Matrix([ws, wz]), qh.subs(bd, 0))
    assert same(W7 * sp.Matrix([ws, wz, bd]), qh)
    # convention: +w_s drives the hub along -y_i, i.e. omnikin's u at delta = theta_i - 90 deg
    assert same(rot2(alp) * sp.Matrix([0, -1]), sp.Matrix([cos(alp - pi / 2), sin(alp - pi / 2)]))
    # with the spin measured about -x_i (left-handed) the matrix would carry +r_i instead
    qh_left = qh.subs(ws, -ws)
    assert wrong_entries(W6 * sp.Matrix([ws, wz]), qh_left.subs(bd, 0)) == [(2, 1)]


def _derived_Ji(qhat, variables, subs=None):
    J = mn_jhat() * qhat
    J = J.jacobian(sp.Matrix(variables))
    if subs:
        J = J.subs(subs)
    return J.applyfunc(lambda e: sp.simplify(trig_reduce(e)))


def test_G06_eq8_conventional_wheel_jacobian():
    rr = sp.Symbol("r_i", positive=True)
    qh, (ws, wz, bd) = conventional_qhat(rr)
    derived = _derived_Ji(qh.subs(bd, 0), [ws, wz])
    _, p, thi = mn_printed_jhat()
    printed = sp.Matrix([[rr * sin(thi), p[1]], [-rr * cos(thi), p[0]], [0, 1]])
    assert wrong_entries(printed, derived) == [(2, 2)]
    corrected = printed.copy()
    corrected[1, 1] = -p[0]
    assert same(corrected, derived)


def _stack(n=3):
    A = sp.Matrix.vstack(*[sp.eye(3)] * n)
    return A


def test_G07_eq9_10_least_squares_is_the_mean():
    b = [sp.Matrix(sp.symbols(f"b{k}_1:4", real=True)) for k in range(3)]
    A, Bq = _stack(), sp.Matrix.vstack(*b)
    V = (A.T * A).inv() * A.T * Bq  # eq 10
    assert sp.expand(A.T * (A * V - Bq)) == sp.zeros(3, 1)  # normal equations: least squares
    assert sp.expand(V - (b[0] + b[1] + b[2]) / 3) == sp.zeros(3, 1)


def test_G08_eq11_12_consistency_projector():
    b = [sp.Matrix(sp.symbols(f"b{k}_1:4", real=True)) for k in range(3)]
    A = _stack()
    Om = A * (A.T * A).inv() * A.T - sp.eye(9)  # eq 11
    Bq = sp.Matrix.vstack(*b)
    mean = (b[0] + b[1] + b[2]) / 3
    assert sp.expand(Om * Bq - sp.Matrix.vstack(*[mean - bk for bk in b])) == sp.zeros(9, 1)
    assert sp.expand(Om * sp.Matrix.vstack(b[0], b[0], b[0])) == sp.zeros(9, 1)  # agreement -> 0


RR_, rr_, LL = sp.symbols("R r L", positive=True)


def test_G09_eq13_omni_wheel_matrix_rows_swapped():
    qh, (wx, wr, wz) = omni_qhat(RR_, rr_)
    printed = sp.Matrix([[0, rr_, 0], [-RR_, 0, 0], [0, 0, 0], [0, 0, 1]]) * sp.Matrix([wx, wr, wz])
    assert wrong_entries(printed, qh) == [(3, 1), (4, 1)]  # slip fed to betadot instead of omega_i
    corrected = sp.Matrix([[0, rr_, 0], [-RR_, 0, 0], [0, 0, 1], [0, 0, 0]]) * sp.Matrix([wx, wr, wz])
    assert same(corrected, qh)


def test_G10_eq14_omni_wheel_jacobian_third_column():
    qh, (wx, wr, wz) = omni_qhat(RR_, rr_)
    derived = _derived_Ji(qh, [wx, wr, wz])
    _, p, thi = mn_printed_jhat()
    c, s = cos(thi), sin(thi)
    # columns 1-2 as printed are right
    assert same(derived[:, :2], sp.Matrix([[RR_ * s, rr_ * c], [-RR_ * c, rr_ * s], [0, 0]]))
    # column 3 printed as (lambda_i, -lambda_i, 1): corrected (p_iy, -p_ix, 1)
    assert same(derived[:, 2], sp.Matrix([p[1], -p[0], 1]))
    # what the printed eq 13 (rows swapped) would give instead: the betadot column of eq 5
    J5, _, _ = mn_printed_jhat()
    assert wrong_entries(J5[:, 3], derived[:, 2]) != []


# --- the triangular robot of Table 1 (002) ---------------------------------------------
S3 = sqrt(3)
LAMBDAS = [(-LL, 0), (LL / 2, LL * S3 / 2), (LL / 2, -LL * S3 / 2)]
ALPHAS = [pi, pi / 3, -pi / 3]


@lru_cache(None)
def garcia_Ji(gamma1=0):
    """Derived 3x3 wheel Jacobians (in (w_x, w_r, w_z)) of the three wheels of Table 1,
    with beta = 0, delta = 0 and gamma = (gamma1, 0, 0)."""
    qh, vars_ = omni_qhat(RR_, rr_)
    J = mn_jhat() * qh
    J = J.jacobian(sp.Matrix(vars_))
    out = []
    for k in range(3):
        g = gamma1 if k == 0 else 0
        sub = {alp: ALPHAS[k], gam: g, bet: 0, delx: 0, dely: 0, lamx: LAMBDAS[k][0], lamy: LAMBDAS[k][1]}
        out.append(J.subs(sub).applyfunc(sp.simplify))
    return tuple(out)


def test_G11_table1_gamma1_must_be_zero():
    J1_table = garcia_Ji(gamma1=pi)[0]  # Table 1 as printed: gamma_1 = 180 deg
    printed15 = sp.Matrix([[0, -rr_, 0], [RR_, 0, LL], [0, 0, 1]])
    assert wrong_entries(printed15, J1_table) == [(1, 2), (2, 1)]
    assert same(printed15, garcia_Ji(gamma1=0)[0])  # the text's gamma_i = 0 reproduces eq 15
    # with gamma_1 = 0 all three wheels drive the hub the same way round (clockwise for +w_x)
    for g1, expected in ((0, [-1, -1, -1]), (pi, [1, -1, -1])):
        senses = []
        for k in range(3):
            theta = ALPHAS[k] + (g1 if k == 0 else 0)
            drive = rot2(theta) * sp.Matrix([0, -1])
            tangent = E90 * sp.Matrix(LAMBDAS[k]) / LL
            senses.append(sp.simplify((drive.T * tangent)[0]))
        assert senses == expected


def test_G12_eq15_J1():
    printed = sp.Matrix([[0, -rr_, 0], [RR_, 0, LL], [0, 0, 1]])
    assert same(printed, garcia_Ji()[0])


def test_G13_eq16_J2_entry_2_2():
    printed = sp.Matrix([[RR_ * S3 / 2, rr_ / 2, LL * S3 / 2], [-RR_ / 2, -rr_ * S3 / 2, -LL / 2], [0, 0, 1]])
    assert wrong_entries(printed, garcia_Ji()[1]) == [(2, 2)]
    printed[1, 1] = rr_ * S3 / 2
    assert same(printed, garcia_Ji()[1])


def test_G14_eq17_J3_entry_2_2():
    printed = sp.Matrix([[-RR_ * S3 / 2, rr_ / 2, -LL * S3 / 2], [-RR_ / 2, rr_ * S3 / 2, -LL / 2], [0, 0, 1]])
    assert wrong_entries(printed, garcia_Ji()[2]) == [(2, 2)]
    printed[1, 1] = -rr_ * S3 / 2
    assert same(printed, garcia_Ji()[2])


def _garcia_AB():
    A = _stack()
    B = sp.diag(*garcia_Ji())
    return A, B


def test_G15_eq18_vehicle_jacobian():
    A, B = _garcia_AB()
    a = 2 * S3
    R, r_, L = RR_, rr_, LL
    printed = sp.Matrix(
        [
            [0, -r_ / 3, 0, R / a, r_ / 6, L / a, -R / a, r_ / 6, -L / a],
            [R / 3, 0, L / 3, -R / 6, r_ / a, -L / 6, -R / 6, -r_ / a, -L / 6],
            [0, 0, Q(1, 3), 0, 0, Q(1, 3), 0, 0, Q(1, 3)],
        ]
    )
    assert same(printed, (A.T * A).inv() * A.T * B)


def test_G16_eq19_no_slip_matrix_three_entries():
    A, B = _garcia_AB()
    derived = (A * (A.T * A).inv() * A.T - sp.eye(9)) * B
    a, s3 = 2 * S3, S3
    R, r_, L = RR_, rr_, LL
    t3 = Q(1, 3)
    printed = sp.Matrix(
        [
            [0, 2 * r_ / 3, 0, R / a, r_ / 6, L / a, -R / a, r_ / 6, -L / a],
            [-2 * r_ / 3, 0, -2 * L / 3, -R / 6, r_ / a, -L / 6, -R / 6, -r_ / a, -L / 6],
            [0, 0, -2 * t3, 0, 0, t3, 0, 0, t3],
            [0, -r_ / 3, 0, -R / s3, -r_ / 3, -L / s3, -R / a, -r_ / 6, -L / a],
            [R / 3, 0, L / 3, R / 3, -r_ / s3, L / 3, -R / 6, -r_ / a, -L / 6],
            [0, 0, t3, 0, 0, -2 * t3, 0, 0, t3],
            [0, -r_ / 3, 0, R / a, r_ / 6, L / a, R / s3, -r_ / 3, -L / s3],
            [R / 3, 0, L / 3, -R / 6, r_ / a, -L / 6, R / 3, r_ / s3, L / 3],
            [0, 0, t3, 0, 0, t3, 0, 0, -2 * t3],
        ]
    )
    assert wrong_entries(printed, derived) == [(2, 1), (4, 8), (7, 9)]
    printed[1, 0], printed[3, 7], printed[6, 8] = -2 * R / 3, r_ / 6, L / s3
    assert same(printed, derived)


WX = sp.symbols("omega_1x omega_2x omega_3x", real=True)


@lru_cache(None)
def garcia_unactuated():
    """Solve eq 19 (derived) for the roller and slip speeds in terms of the wheel speeds."""
    A, B = _garcia_AB()
    Om = A * (A.T * A).inv() * A.T - sp.eye(9)
    wr = sp.symbols("omega_1r omega_2r omega_3r", real=True)
    wz = sp.symbols("omega_1z omega_2z omega_3z", real=True)
    q = sp.Matrix([v for k in range(3) for v in (WX[k], wr[k], wz[k])])
    sol = sp.solve(list(Om * B * q), list(wr) + list(wz), dict=True)[0]
    return {k: sp.simplify(v) for k, v in sol.items()}, wr, wz, q


def test_G17_eq20_22_roller_speeds():
    sol, wr, wz, q = garcia_unactuated()
    R, r_ = RR_, rr_
    printed = [R * (WX[2] - WX[1]) / (r_ * S3), R * (WX[0] - WX[2]) / (r_ * S3), R * (WX[1] - WX[0]) / (r_ * S3)]
    for k in range(3):
        assert sp.simplify(sol[wr[k]] - printed[k]) == 0


def test_G18_eq23_slip_sign():
    sol, wr, wz, q = garcia_unactuated()
    printed = RR_ * (WX[0] + WX[1] + WX[2]) / (3 * LL)
    assert wrong_entries(printed, sol[wz[0]]) == [(1, 1)]
    assert sp.simplify(-printed - sol[wz[0]]) == 0


def test_G19_eq24_25_equal_slips():
    sol, wr, wz, q = garcia_unactuated()
    assert sp.simplify(sol[wz[1]] - sol[wz[0]]) == 0 and sp.simplify(sol[wz[2]] - sol[wz[0]]) == 0


@lru_cache(None)
def garcia_fk():
    """V_c = J q (eq 10) with the derived roller and slip speeds substituted: 3x3 FK matrix."""
    A, B = _garcia_AB()
    sol, wr, wz, q = garcia_unactuated()
    V = ((A.T * A).inv() * A.T * B * q).subs(sol).applyfunc(sp.simplify)
    return V.jacobian(sp.Matrix(WX)).applyfunc(sp.simplify), V


def test_G20_eq26_vx():
    _, V = garcia_fk()
    assert sp.simplify(V[0] - RR_ * (WX[1] - WX[2]) / S3) == 0


def test_G21_eq27_vy_typo():
    _, V = garcia_fk()
    printed = RR_ * (2 * WX[1] - WX[1] - WX[2]) / 3
    assert wrong_entries(printed, V[1]) == [(1, 1)]
    assert sp.simplify(RR_ * (2 * WX[0] - WX[1] - WX[2]) / 3 - V[1]) == 0


def test_G22_eq28_omega_signs():
    _, V = garcia_fk()
    printed = -RR_ * (WX[0] - WX[1] - WX[2]) / (3 * LL)
    assert wrong_entries(printed, V[2]) == [(1, 1)]
    assert sp.simplify(-RR_ * (WX[0] + WX[1] + WX[2]) / (3 * LL) - V[2]) == 0


def garcia_eq29(corrected: bool):
    R, L = RR_, LL
    return sp.Matrix(
        [
            [0, R / S3, (-1 if corrected else 1) * R / S3],
            [2 * R / 3, -R / 3, -R / 3],
            [-R / (3 * L), -R / (3 * L), -R / (3 * L)],
        ]
    )


def garcia_eq30():
    R, L = RR_, LL
    return sp.Matrix([[0, 1 / R, -L / R], [S3 / (2 * R), -1 / (2 * R), -L / R], [-S3 / (2 * R), -1 / (2 * R), -L / R]])


def test_G23_eq29_entry_1_3():
    F, _ = garcia_fk()
    assert wrong_entries(garcia_eq29(False), F) == [(1, 3)]
    assert same(garcia_eq29(True), F)


def test_G24_eq30_inverse_jacobian():
    F, _ = garcia_fk()
    assert same(garcia_eq30(), F.inv())
    assert same(garcia_eq30() * garcia_eq29(True), sp.eye(3))
    assert wrong_entries(garcia_eq30() * garcia_eq29(False), sp.eye(3)) != []  # not the printed eq 29
    # independently: IK straight from the rigid-body hub velocity and the no-slip of each wheel
    for k in range(3):
        vp = body_point_velocity(LAMBDAS[k])
        drive = rot2(ALPHAS[k]) * sp.Matrix([0, -1])  # +w_x about +x_i drives the hub along -y_i
        assert same((drive.T * vp)[0] / RR_, (garcia_eq30()[k, :] * TWIST)[0])


# ====================================================================================
# Villasenor et al. (seed 004)
# ====================================================================================


def test_V01_eq3_homogeneous_matrix_last_row():
    a, px, py, pz = sp.symbols("a p_x p_y p_z", real=True)
    rot = sp.Matrix([[cos(a), -sin(a), 0], [sin(a), cos(a), 0], [0, 0, 1]])
    printed = rot.row_join(sp.Matrix([px, py, pz])).col_join(sp.Matrix([[0, 0, 0, 0]]))
    assert printed.det() == 0  # as printed (last row 0 0 0 0) it has no inverse: eq 4 cannot hold
    corrected = rot.row_join(sp.Matrix([px, py, pz])).col_join(sp.Matrix([[0, 0, 0, 1]]))
    assert trig_zero(corrected.det() - 1)


def test_V02_eq4_5_inverse_transform():
    a, dx_, dy_, dz_ = sp.symbols("a d_x d_y d_z", real=True)
    P = sp.Matrix([[cos(a), -sin(a), 0, dx_], [sin(a), cos(a), 0, dy_], [0, 0, 1, dz_], [0, 0, 0, 1]])  # eq 5
    n, o, aa, p = P[:3, 0], P[:3, 1], P[:3, 2], P[:3, 3]
    inv4 = sp.Matrix(
        [[n[0], n[1], n[2], -p.dot(n)], [o[0], o[1], o[2], -p.dot(o)], [aa[0], aa[1], aa[2], -p.dot(aa)], [0, 0, 0, 1]]
    )  # eq 4
    assert same(inv4 * P, sp.eye(4))


def test_V03_eq6_7_contact_frame_pose():
    p, T_CR, _ = mn_chain()
    assert same(p, sp.Matrix([lamx, lamy]) + rot2(alp + bet) * sp.Matrix([delx, dely]))
    assert same(T_CR[:2, :2], rot2(alp + bet + gam))


def test_V04_eq8_wheel_jacobian_hat():
    J, _, _ = mn_printed_jhat()  # eq 8 of 004 is identical to eq 5 of 002
    assert same(J, mn_jhat())


def test_V05_eq10_steerable_wheel_matrix_variable_names():
    rr = sp.Symbol("r_i", positive=True)
    qh, (ws, wz, bd) = conventional_qhat(rr)
    W10 = sp.Matrix([[0, 0, 0], [-rr, 0, 0], [0, 1, 0], [0, 0, 1]])
    # holds with omega_ix = wheel spin (about +x_i) and omega_iy = rotational slip omega_i
    assert same(W10 * sp.Matrix([ws, wz, bd]), qh)
    # with the text's reading (omega_ix the slewing speed betadot, omega_iy the wheel spin) it fails
    assert wrong_entries(W10 * sp.Matrix([bd, ws, wz]), qh) != []


def test_V06_eq11_two_entries():
    rr = sp.Symbol("r_i", positive=True)
    qh, (ws, wz, bd) = conventional_qhat(rr)
    derived = _derived_Ji(qh, [ws, wz, bd])
    _, p, thi = mn_printed_jhat()
    printed = sp.Matrix([[rr * sin(thi), p[1], -lamy], [-rr * cos(thi), p[0], lamx], [0, 0, -1]])
    assert wrong_entries(printed, derived) == [(2, 2), (3, 2)]
    printed[1, 1], printed[2, 1] = -p[0], 1
    assert same(printed, derived)


def test_V07_eq12_15_least_squares():
    b = [sp.Matrix(sp.symbols(f"c{k}_1:4", real=True)) for k in range(3)]
    A, Bq = _stack(), sp.Matrix.vstack(*b)
    V = (A.T * A).inv() * A.T * Bq  # eq 14
    assert sp.expand(A.T * (A * V - Bq)) == sp.zeros(3, 1)
    assert sp.expand(V - (b[0] + b[1] + b[2]) / 3) == sp.zeros(3, 1)


def test_V08_eq16_19_copied_from_002():
    F, V = garcia_fk()
    p16 = RR_ * (WX[1] - WX[2]) / S3
    p17 = RR_ * (2 * WX[1] - WX[1] - WX[2]) / 3
    p18 = -RR_ * (WX[0] - WX[1] - WX[2]) / (3 * LL)
    assert sp.simplify(p16 - V[0]) == 0
    assert wrong_entries(sp.Matrix([p17, p18]), V[1:, :]) == [(1, 1), (2, 1)]
    assert wrong_entries(garcia_eq29(False), F) == [(1, 3)]  # eq 19 == eq 29 of 002
    # and they cannot describe the robot of Table 1 of 004: its hips are not on one circle
    lam = [(Q(-6186, 100), Q(5672, 100)), (Q(-13686, 100), Q(-7319, 100)), (Q(1314, 100), Q(-7319, 100))]
    radii = [sqrt(x**2 + y**2) for x, y in lam]
    assert len({sp.N(rad, 6) for rad in radii}) == 3


# ====================================================================================
# Burgard & Krawez, Wheeled Locomotion slides (seed 003)
# ====================================================================================

V, om, ll, dd = sp.symbols("V omega l d", real=True)
x0, y0, th0 = sp.symbols("x y theta", real=True)
vl, vr = sp.symbols("v_l v_r", real=True)


def _diff_drive_wheels():
    """Rim speeds of the left (y = +l/2) and right (y = -l/2) wheels for the twist (V, 0, om)."""
    sub = {vx: V, vy: 0, w: om}
    left = body_point_velocity((0, ll / 2)).subs(sub)
    right = body_point_velocity((0, -ll / 2)).subs(sub)
    return left, right


def test_B01_icc_position():
    sub = {vx: V, vy: 0, w: om}
    px, py = sp.symbols("p_x p_y", real=True)
    sol = sp.solve(list(body_point_velocity((px, py)).subs(sub)), [px, py], dict=True)[0]
    icc_body = sp.Matrix([sol[px], sol[py]])  # the body point at rest
    icc_world = sp.Matrix([x0, y0]) + rot2(th0) * icc_body
    Rs = V / om  # R signed: > 0 when the ICC is on the left (counter-clockwise turn)
    printed = sp.Matrix([x0 - Rs * sin(th0), y0 + Rs * cos(th0)])
    assert same(printed, icc_world)
    assert wrong_entries(sp.Matrix([x0 + Rs * sin(th0), y0 - Rs * cos(th0)]), icc_world) != []  # R>0 right


def test_B02_wheel_speeds_about_icc():
    left, right = _diff_drive_wheels()
    Rs = V / om
    assert left[1] == 0 and right[1] == 0  # the wheels roll along their own y-less direction
    assert sp.simplify(om * (Rs + ll / 2) - right[0]) == 0
    assert sp.simplify(om * (Rs - ll / 2) - left[0]) == 0


def test_B03_R_omega_V_from_wheel_speeds():
    left, right = _diff_drive_wheels()
    sol = sp.solve([left[0] - vl, right[0] - vr], [V, om], dict=True)[0]
    assert sp.simplify(sol[om] - (vr - vl) / ll) == 0
    assert sp.simplify(sol[V] - (vr + vl) / 2) == 0
    assert sp.simplify(sol[V] / sol[om] - ll / 2 * (vl + vr) / (vr - vl)) == 0


def test_B04_motion_patterns():
    Rf = ll / 2 * (vl + vr) / (vr - vl)
    wf = (vr - vl) / ll
    L_, a_, b_ = sp.symbols("L a b", positive=True)
    assert wf.subs(vl, vr) == 0  # v_l = v_r: straight line
    assert sp.simplify(Rf.subs(vl, -vr)) == 0  # v_l = -v_r: turn on the spot
    assert sp.simplify(Rf.subs(vl, 0) - ll / 2) == 0  # v_l = 0: pivot about the left wheel
    # 0 < v_l < v_r: ICC to the left, outside the axle
    expr = sp.simplify(Rf.subs({ll: L_, vl: a_, vr: a_ + b_}) - L_ / 2)
    assert expr.is_positive


def test_B05_rotation_about_icc_is_exact():
    dt = sp.Symbol("delta_t", real=True)
    Rs = V / om  # omega != 0
    icc = sp.Matrix([x0 - Rs * sin(th0), y0 + Rs * cos(th0)])
    M = sp.Matrix([[cos(om * dt), -sin(om * dt), 0], [sin(om * dt), cos(om * dt), 0], [0, 0, 1]])
    printed = M * sp.Matrix([x0 - icc[0], y0 - icc[1], th0]) + sp.Matrix([icc[0], icc[1], om * dt])
    # it solves xdot = V cos(theta), ydot = V sin(theta), thetadot = omega (constant V, omega) ...
    rhs = sp.Matrix([V * cos(printed[2]), V * sin(printed[2]), om])
    k = sp.Symbol("k", real=True)  # omega*dt as one angle for the identity test
    assert same((printed.diff(dt) - rhs).subs(dt, k / om), sp.zeros(3, 1))
    # ... from the initial pose, so by uniqueness it is the exact motion over delta_t
    assert sp.simplify(printed.subs(dt, 0) - sp.Matrix([x0, y0, th0])) == sp.zeros(3, 1)
    # a rotation by -omega dt (the wrong way round) does not solve it
    Mw = M.subs(om * dt, -om * dt)
    wrong = Mw * sp.Matrix([x0 - icc[0], y0 - icc[1], th0]) + sp.Matrix([icc[0], icc[1], om * dt])
    assert wrong_entries(wrong.diff(dt), rhs) != []


def test_B06_forward_kinematics_integrals():
    left, right = _diff_drive_wheels()
    sol = sp.solve([left[0] - vl, right[0] - vr], [V, om], dict=True)[0]
    # world rates of a body with twist (V, 0, omega): R(theta) (V, 0), thetadot = omega
    rates = rot2(th0) * sp.Matrix([V, 0])
    printed_general = sp.Matrix([V * cos(th0), V * sin(th0)])
    assert same(printed_general, rates)
    printed_dd = sp.Matrix([(vr + vl) / 2 * cos(th0), (vr + vl) / 2 * sin(th0), (vr - vl) / ll])
    assert same(printed_dd, sp.Matrix([rates[0], rates[1], om]).subs({V: sol[V], om: sol[om]}))


def test_B07_ackermann_R_equals_d_over_tan_phi():
    halftrack = sp.Symbol("h", positive=True)  # l/2
    Rs = sp.Symbol("R", positive=True)
    # fixed rear wheels at (0, +-h) rolling along x: their no-side-slip rows force vy = 0
    for y in (halftrack, -halftrack):
        assert body_point_velocity((0, y))[1] == vy
    sub = {vx: om * Rs, vy: 0, w: om}  # ICC at (0, R) on the rear axle line
    # virtual middle front wheel at (d, 0): its velocity sets the steering angle phi
    vf = body_point_velocity((dd, 0)).subs(sub)
    assert sp.simplify(vf[1] / vf[0] - dd / Rs) == 0  # tan(phi) = d / R  <=>  R = d / tan(phi)
    # the real front wheels at (d, +-h): tan(phi_{L,R}) = d / (R -+ h)
    for y, expected in ((halftrack, dd / (Rs - halftrack)), (-halftrack, dd / (Rs + halftrack))):
        vw = body_point_velocity((dd, y)).subs(sub)
        assert sp.simplify(vw[1] / vw[0] - expected) == 0
    # the slide's rear-wheel relations omega (R +- l/2) = v_{r,l}
    assert sp.simplify(body_point_velocity((0, -halftrack)).subs(sub)[0] - om * (Rs + halftrack)) == 0
    assert sp.simplify(body_point_velocity((0, halftrack)).subs(sub)[0] - om * (Rs - halftrack)) == 0


def test_B08_synchro_drive_theta_is_the_steering_direction():
    vv, phi, psi = sp.symbols("v phi psi", real=True)
    sub = {vx: vv * cos(phi), vy: vv * sin(phi), w: 0}
    for p in [(Q(1, 5), 0), (-Q(1, 10), Q(17, 100)), (-Q(1, 10), -Q(17, 100))]:
        hub = body_point_velocity(p).subs(sub)
        assert same(hub, vv * sp.Matrix([cos(phi), sin(phi)]))  # every wheel steered to phi, speed v
    world = rot2(psi) * sp.Matrix([vv * cos(phi), vv * sin(phi)])  # chassis heading psi fixed
    assert same(world, vv * sp.Matrix([cos(psi + phi), sin(psi + phi)]))  # theta = psi + phi


def test_B09_xr4000_integrals_need_course_angle():
    psi = sp.Symbol("psi", real=True)  # body heading
    speed = sqrt(vx**2 + vy**2)
    course = psi + sp.atan2(vy, vx)
    world = rot2(psi) * sp.Matrix([vx, vy])
    slide = sp.Matrix([speed * cos(course), speed * sin(course)])
    pt = {vx: Q(3, 10), vy: Q(2, 5), psi: Q(7, 10)}
    assert all(abs(sp.N((slide - world)[i].subs(pt))) < 1e-12 for i in range(2))  # theta = course angle
    heading_read = sp.Matrix([speed * cos(psi), speed * sin(psi)])  # theta = body heading
    assert wrong_entries(heading_read.subs(pt), world.subs(pt)) == [(1, 1), (2, 1)]


@lru_cache(None)
def mecanum_rim_speeds():
    """r*omega_i of the four wheels of mecanum4 (drive +x, rollers -45 FL/RR, +45 FR/RL), from the
    3-D no-slip of wheel and roller; half wheelbase a, half track b."""
    a_, b_, R, rho = sp.symbols("a b R rho", positive=True)
    layout = {"FL": (a_, b_, -pi / 4), "FR": (a_, -b_, pi / 4), "RL": (-a_, b_, pi / 4), "RR": (-a_, -b_, -pi / 4)}
    out = {}
    for name, (x, y, g) in layout.items():
        ww, _ = swedish_no_slip(body_point_velocity((x, y)), 0, g, R, rho)
        out[name] = sp.expand(sp.simplify(R * ww))
    return out, a_, b_


def _burgard(v):
    return {
        "v_y": (v[0] + v[1] + v[2] + v[3]) / 4,
        "v_x": (v[0] - v[1] + v[2] - v[3]) / 4,
        "v_theta": (v[0] - v[1] - v[2] + v[3]) / 4,
        "v_error": (v[0] + v[1] - v[2] - v[3]) / 4,
    }


def test_B10_mecanum_relations_numbering_and_frame():
    rim, a_, b_ = mecanum_rim_speeds()
    # wheel numbering v0..v3 = rear_right, rear_left, front_left, front_right (clockwise from the
    # rear right seen from above); Burgard's frame: x to the right (= -y), y forward (= +x)
    v = [rim[n] for n in ("RR", "RL", "FL", "FR")]
    b = _burgard(v)
    assert sp.expand(b["v_y"] - vx) == 0
    assert sp.expand(b["v_x"] - (-vy)) == 0
    assert sp.expand(b["v_theta"] - (a_ + b_) * w) == 0  # m/s: (a + b) omega
    assert sp.expand(b["v_error"]) == 0  # zero without slip
    # omnikin's file order (FL, FR, RL, RR) satisfies the relations in no frame (8 signed axis
    # permutations), nor with v_theta = -(a + b) omega
    frames = []
    for perm in ((0, 1), (1, 0)):
        for s1, s2 in itertools.product((1, -1), repeat=2):
            M = sp.zeros(2)
            M[0, perm[0]], M[1, perm[1]] = s1, s2
            frames.append(M)

    def holds(order):
        bb = _burgard([rim[n] for n in order])
        return any(
            sp.expand(bb["v_x"] - (M * sp.Matrix([vx, vy]))[0]) == 0
            and sp.expand(bb["v_y"] - (M * sp.Matrix([vx, vy]))[1]) == 0
            and sp.expand(bb["v_error"]) == 0
            and sp.expand(bb["v_theta"] ** 2 - ((a_ + b_) * w) ** 2) == 0
            for M in frames
        )

    assert not holds(("FL", "FR", "RL", "RR"))
    assert holds(("RR", "RL", "FL", "FR"))


def test_B11_non_holonomic_classification():
    # differential drive: sliding rows of two fixed wheels on one axle -> rank 1, vy = 0 forced
    rows = []
    for y in (ll / 2, -ll / 2):
        n = sp.Matrix([[0, 1]])  # no side slip: (-sin 0, cos 0) . v_p = 0
        rows.append((n * body_point_velocity((0, y))).jacobian(TWIST))
    assert sp.Matrix.vstack(*rows).rank() == 1  # 3 - 1 = 2 admissible directions: non-holonomic
    # synchro drive (centred steered wheels aligned with a generic motion): rank 2 -> one direction
    twist = {vx: Q(3, 10), vy: Q(1, 5), w: Q(1, 2)}
    rows = []
    for p in [(Q(1, 5), 0), (-Q(1, 10), Q(17, 100)), (-Q(1, 10), -Q(17, 100))]:
        hub = body_point_velocity(p).subs(twist)
        nrm = sp.Matrix([[-hub[1], hub[0]]])  # normal of the wheel plane, aligned with the hub
        rows.append((nrm * body_point_velocity(p)).jacobian(TWIST))
    assert sp.Matrix.vstack(*rows).rank() == 2
    # mecanum: no sliding constraint, and the four rolling rows have rank 3: any twist, holonomic
    rim, a_, b_ = mecanum_rim_speeds()
    J = sp.Matrix([[rim[n]] for n in ("FL", "FR", "RL", "RR")]).jacobian(TWIST)
    assert J.rank() == 3
