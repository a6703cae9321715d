"""Trajectory metrics in the plane: absolute trajectory error (ATE) and relative pose error (RPE).

The definitions are those of the TUM RGB-D benchmark (Sturm et al., IROS 2012) as evaluated
by ``evo`` (``evo_ape ... --pose_relation trans_part [--align]`` and
``evo_rpe ... --delta N --delta_unit f``), written for 2D poses ``(x, y, theta)``. For
trajectories in the plane the numbers are the same as evo's (checked by a test against evo
when it is installed; omnikin does not depend on it).

Trajectories are ``(t, poses)``: timestamps ``t`` ``(N,)`` [s], strictly increasing, and
poses ``(N, 3)`` [m, m, rad] of the body in the world frame. The reference ("ground truth")
is ``Q``, the estimate ``P``.

**Association** (:func:`associate`, evo's ``--t_max_diff`` and ``--t_offset``): every pose of
the trajectory with fewer poses (the estimate when both have as many) is paired with the
pose of the other whose timestamp is nearest, the estimate's timestamps shifted by
``offset``; ties go to the earlier timestamp; a pair is kept when the timestamps differ by at
most ``max_diff``. A pose of the longer trajectory can be paired more than once. The metrics
below run over the ``M`` associated pairs ``(Q_i, P_i)``.

**SE(2) alignment** (:func:`align_se2`; Horn 1987, Umeyama 1991 without scale, closed form
in the plane): the rigid motion ``(R(phi), s)`` minimising
``sum_i |q_i - (R(phi) p_i + s)|^2`` over the estimated positions ``p_i`` and reference
positions ``q_i`` is, with centroids ``p_bar``, ``q_bar`` and ``a_i = p_i - p_bar``,
``b_i = q_i - q_bar``::

    C = sum_i a_i . b_i,     S = sum_i a_i x b_i = sum_i (a_ix b_iy - a_iy b_ix),
    phi = atan2(S, C),       s = q_bar - R(phi) p_bar.

It is undefined (and refused) when ``C = S = 0``: all positions of one trajectory coincide.
evo aligns in 3D; for trajectories in the plane its rotation is this one about z as long as
the best fit is not a mirror image (then a 3D rotation can flip the plane over), and its 3D
alignment fails on collinear positions, where this one is defined.

**ATE** (:func:`ate`): per pair the translation error ``e_i = |q_i - (R p_i + s)|`` [m], with
``R = I, s = 0`` without alignment; statistics over ``i``.

**RPE** (:func:`rpe`, ``delta`` in frames): index pairs ``(i, j = i + delta)`` of the
associated poses, consecutive and non-overlapping ``(0, d), (d, 2d), ...`` by default (evo's
default) or every ``(i, i + d)`` with ``all_pairs``. Per pair the error pose is::

    E_ij = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j)      (SE(2) products, evo's rpe_base)

with translation part ``|t(E_ij)|`` [m] and rotation part ``|wrap(theta(E_ij))|`` [rad or deg]
(the angle of the rotation, in ``[0, pi]``). RPE does not depend on alignment.

**Statistics** (:func:`statistics`, evo's): ``rmse = sqrt(mean(e^2))``, ``mean``, ``median``,
``std`` (population, ``sqrt(mean((e - mean)^2))``), ``min``, ``max``, ``sse = sum(e^2)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..common.arrays import as_real_array, as_real_scalar
from ..errors import MetricsInputError
from ..kinematics.se2 import between, compose, wrap_angle


# --- input checks ------------------------------------------------------------------------------------
def check_trajectory(t, poses, name: str = "trajectory") -> tuple[np.ndarray, np.ndarray]:
    """``(t (N,), poses (N, 3))`` as float arrays, or :class:`MetricsInputError` naming ``name``.

    Requires at least one pose, matching lengths, finite values and strictly increasing times.
    """
    tt = as_real_array(t, f"{name}: timestamps", MetricsInputError)
    p = as_real_array(poses, f"{name}: poses", MetricsInputError)
    if tt.ndim != 1:
        raise MetricsInputError(f"{name}: timestamps must be a 1-D array, got shape {tt.shape}")
    if p.ndim != 2 or p.shape[1] != 3:
        raise MetricsInputError(f"{name}: poses must have shape (N, 3) (x, y, theta), got {p.shape}")
    if len(tt) == 0 or len(p) == 0:
        raise MetricsInputError(f"{name}: empty trajectory (no poses)")
    if len(tt) != len(p):
        raise MetricsInputError(f"{name}: {len(tt)} timestamps but {len(p)} poses")
    bad = np.flatnonzero(~np.isfinite(tt))
    if bad.size:
        raise MetricsInputError(f"{name}: non-finite timestamp {float(tt[bad[0]])} at pose {bad[0]}")
    where = np.argwhere(~np.isfinite(p))
    if where.size:
        i, j = where[0]
        raise MetricsInputError(f"{name}: non-finite {'xy'[j] if j < 2 else 'theta'} {float(p[i, j])} at pose {i}")
    back = np.flatnonzero(np.diff(tt) <= 0)
    if back.size:
        k = back[0] + 1
        raise MetricsInputError(
            f"{name}: timestamps must increase strictly; pose {k} at t={float(tt[k]):.9g} follows "
            f"t={float(tt[k - 1]):.9g}"
        )
    return tt, p


# --- statistics ------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Statistics:
    """Summary of an error sequence (module docstring); units those of the errors."""

    rmse: float
    mean: float
    median: float
    std: float
    min: float
    max: float
    sse: float
    count: int

    def as_dict(self) -> dict:
        return {k: getattr(self, k) for k in ("rmse", "mean", "median", "std", "min", "max", "sse", "count")}


def statistics(errors) -> Statistics:
    """:class:`Statistics` of a non-empty 1-D error array."""
    e = as_real_array(errors, "statistics: errors", MetricsInputError)
    if e.ndim != 1 or e.size == 0:
        raise MetricsInputError(f"statistics need a non-empty 1-D error array, got shape {e.shape}")
    if not np.all(np.isfinite(e)):
        raise MetricsInputError("statistics: non-finite error value")
    sq = e * e
    return Statistics(
        rmse=float(math.sqrt(np.mean(sq))),
        mean=float(np.mean(e)),
        median=float(np.median(e)),
        std=float(np.std(e)),
        min=float(np.min(e)),
        max=float(np.max(e)),
        sse=float(np.sum(sq)),
        count=int(e.size),
    )


# --- association -----------------------------------------------------------------------------------------
def _nearest(query: np.ndarray, stamps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index into sorted ``stamps`` nearest to each query (ties to the earlier) and the distance."""
    n = len(stamps)
    i = np.searchsorted(stamps, query, side="right")
    lo = np.clip(i - 1, 0, n - 1)
    hi = np.clip(i, 0, n - 1)
    d_lo = np.where(i > 0, query - stamps[lo], np.inf)
    d_hi = np.where(i < n, stamps[hi] - query, np.inf)
    take_hi = d_hi < d_lo
    return np.where(take_hi, hi, lo), np.where(take_hi, d_hi, d_lo)


def associate(t_ref, t_est, max_diff: float = 0.01, offset: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs ``(i_ref, i_est)`` of poses with matching timestamps (module docstring).

    ``max_diff`` [s] >= 0: largest accepted time difference; ``offset`` [s]: added to the
    estimate's timestamps before matching. Both inputs must be strictly increasing
    (see :func:`check_trajectory`). Raises :class:`MetricsInputError` if nothing matches.
    """
    tr = as_real_array(t_ref, "reference: timestamps", MetricsInputError)
    te = as_real_array(t_est, "estimate: timestamps", MetricsInputError)
    max_diff = as_real_scalar(max_diff, "max_diff", MetricsInputError)
    offset = as_real_scalar(offset, "offset", MetricsInputError)
    if not (math.isfinite(max_diff) and max_diff >= 0):
        raise MetricsInputError(f"max_diff must be a finite number of seconds >= 0, got {max_diff!r}")
    if not math.isfinite(offset):
        raise MetricsInputError(f"offset must be a finite number of seconds, got {offset!r}")
    for name, t in (("reference", tr), ("estimate", te)):
        if t.ndim != 1 or t.size == 0:
            raise MetricsInputError(f"{name}: timestamps must be a non-empty 1-D array, got shape {t.shape}")
        if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise MetricsInputError(f"{name}: timestamps must be finite and increase strictly")
    if len(te) > len(tr):  # walk the reference (the shorter), match into the estimate
        j, d = _nearest(tr, te + offset)
        keep = d <= max_diff
        i_ref, i_est = np.flatnonzero(keep), j[keep]
    else:  # walk the estimate, match into the reference
        j, d = _nearest(te, tr - offset)
        keep = d <= max_diff
        i_ref, i_est = j[keep], np.flatnonzero(keep)
    if i_ref.size == 0:
        raise MetricsInputError(
            f"no matching timestamps between reference ({len(tr)} poses, t {tr[0]:.9g}..{tr[-1]:.9g} s) and "
            f"estimate ({len(te)} poses, t {te[0]:.9g}..{te[-1]:.9g} s) within max_diff {max_diff:g} s"
            + (f" and offset {offset:g} s" if offset else "")
        )
    return i_ref.astype(np.intp), i_est.astype(np.intp)


# --- alignment ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Alignment:
    """The rigid motion ``x -> R(theta) x + (x, y)`` that maps the estimate onto the reference."""

    x: float
    y: float
    theta: float

    @property
    def pose(self) -> np.ndarray:
        return np.array([self.x, self.y, self.theta])

    def apply(self, poses) -> np.ndarray:
        """Aligned poses ``(..., 3)``: positions moved and headings turned by ``theta``."""
        return compose(self.pose, as_real_array(poses, "poses", MetricsInputError))

    def as_dict(self) -> dict:
        return {"x": self.x, "y": self.y, "theta": self.theta, "theta_deg": math.degrees(self.theta)}


def align_se2(ref_xy, est_xy) -> Alignment:
    """Closed-form least-squares SE(2) alignment of ``est_xy`` ``(M, 2)`` onto ``ref_xy`` (module docstring)."""
    q = as_real_array(ref_xy, "alignment: reference positions", MetricsInputError)
    p = as_real_array(est_xy, "alignment: estimated positions", MetricsInputError)
    if q.shape != p.shape or q.ndim != 2 or q.shape[1] != 2 or q.shape[0] == 0:
        raise MetricsInputError(
            f"alignment needs two (M, 2) position arrays of the same shape, got {q.shape} and {p.shape}"
        )
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(p))):
        raise MetricsInputError("alignment: non-finite position")
    qb, pb = q.mean(axis=0), p.mean(axis=0)
    a, b = p - pb, q - qb
    c = float(np.sum(a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1]))
    s = float(np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]))
    scale = math.sqrt(float(np.sum(a * a)) * float(np.sum(b * b)))
    if not math.hypot(c, s) > 1e-12 * scale or scale == 0.0:
        raise MetricsInputError(
            f"SE(2) alignment is undefined for these {len(q)} associated poses: all positions of the "
            f"{'estimate' if np.sum(a * a) <= np.sum(b * b) else 'reference'} coincide (or the two are "
            f"uncorrelated); drop --align or use a longer trajectory"
        )
    theta = math.atan2(s, c)
    ct, st = math.cos(theta), math.sin(theta)
    tx = qb[0] - (ct * pb[0] - st * pb[1])
    ty = qb[1] - (st * pb[0] + ct * pb[1])
    return Alignment(float(tx), float(ty), float(theta))


# --- ATE -------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ATEResult:
    """Absolute trajectory error on translation over the associated poses.

    ``errors`` ``(M,)`` [m]; ``t`` ``(M,)`` the reference times of the pairs;
    ``index_ref``/``index_est`` ``(M,)`` the associated pose indices; ``alignment`` the
    SE(2) alignment applied to the estimate (None without); ``stats`` over ``errors``.
    """

    errors: np.ndarray
    t: np.ndarray
    index_ref: np.ndarray
    index_est: np.ndarray
    alignment: Alignment | None
    stats: Statistics

    def as_dict(self) -> dict:
        return {
            "pairs": int(self.errors.size),
            "aligned": self.alignment is not None,
            "alignment": None if self.alignment is None else self.alignment.as_dict(),
            "translation": self.stats.as_dict(),
            "unit": "m",
        }


def _associated(t_ref, ref, t_est, est, max_diff, offset):
    tr, qr = check_trajectory(t_ref, ref, "reference")
    te, pe = check_trajectory(t_est, est, "estimate")
    i_ref, i_est = associate(tr, te, max_diff, offset)
    return tr, qr[i_ref], pe[i_est], i_ref, i_est


def ate(t_ref, ref, t_est, est, *, align: bool = False, max_diff: float = 0.01, offset: float = 0.0) -> ATEResult:
    """Absolute trajectory error (translation) of ``(t_est, est)`` against ``(t_ref, ref)``.

    ``align``: apply the SE(2) alignment of the associated positions first (``evo_ape --align``);
    ``max_diff``, ``offset`` [s]: timestamp association (:func:`associate`).
    """
    tr, q, p, i_ref, i_est = _associated(t_ref, ref, t_est, est, max_diff, offset)
    alignment = None
    if align:
        alignment = align_se2(q[:, :2], p[:, :2])
        p = alignment.apply(p)
    e = np.hypot(q[:, 0] - p[:, 0], q[:, 1] - p[:, 1])
    return ATEResult(e, tr[i_ref], i_ref, i_est, alignment, statistics(e))


# --- RPE -------------------------------------------------------------------------------------------------
ANGLE_UNITS = ("rad", "deg")


@dataclass(frozen=True)
class RPEResult:
    """Relative pose error for a fixed ``delta`` in frames (of the associated poses).

    ``pairs`` ``(K, 2)`` indices into the associated poses; ``translation`` ``(K,)`` [m];
    ``rotation`` ``(K,)`` in ``angle_unit``; ``index_ref``/``index_est`` the association;
    statistics of both parts.
    """

    delta: int
    all_pairs: bool
    pairs: np.ndarray
    translation: np.ndarray
    rotation: np.ndarray
    angle_unit: str
    index_ref: np.ndarray
    index_est: np.ndarray
    translation_stats: Statistics
    rotation_stats: Statistics

    def as_dict(self) -> dict:
        return {
            "delta": self.delta,
            "delta_unit": "frames",
            "all_pairs": self.all_pairs,
            "pairs": int(self.translation.size),
            "translation": self.translation_stats.as_dict(),
            "translation_unit": "m",
            "rotation": self.rotation_stats.as_dict(),
            "rotation_unit": self.angle_unit,
        }


def index_pairs(n: int, delta: int, all_pairs: bool = False) -> np.ndarray:
    """Index pairs ``(K, 2)`` for ``n`` poses: ``(0, d), (d, 2d), ...`` or every ``(i, i + d)``."""
    if all_pairs:
        i = np.arange(max(n - delta, 0))
    else:
        i = np.arange(0, n, delta)[:-1] if n > 0 else np.arange(0)
    return np.column_stack([i, i + delta]).astype(np.intp)


def relative_errors(ref, est, pairs) -> np.ndarray:
    """Error poses ``E_ij = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j)`` ``(K, 3)`` for index ``pairs`` ``(K, 2)``."""
    q = as_real_array(ref, "reference poses", MetricsInputError)
    p = as_real_array(est, "estimated poses", MetricsInputError)
    i, j = pairs[:, 0], pairs[:, 1]
    return between(between(q[i], q[j]), between(p[i], p[j]))


def rpe(
    t_ref,
    ref,
    t_est,
    est,
    *,
    delta: int = 1,
    all_pairs: bool = False,
    angle_unit: str = "rad",
    max_diff: float = 0.01,
    offset: float = 0.0,
) -> RPEResult:
    """Relative pose error over ``delta`` frames of the associated poses (module docstring).

    ``angle_unit``: ``rad`` or ``deg`` for the rotation part.
    """
    if isinstance(delta, bool) or not isinstance(delta, (int, np.integer)) or delta < 1:
        raise MetricsInputError(f"delta must be a whole number of frames >= 1, got {delta!r}")
    if angle_unit not in ANGLE_UNITS:
        raise MetricsInputError(f"angle_unit must be one of {list(ANGLE_UNITS)}, got {angle_unit!r}")
    _, q, p, i_ref, i_est = _associated(t_ref, ref, t_est, est, max_diff, offset)
    if len(q) <= delta:
        raise MetricsInputError(f"RPE with delta {delta} frames needs more than {delta} associated poses, got {len(q)}")
    pairs = index_pairs(len(q), int(delta), all_pairs)
    err = relative_errors(q, p, pairs)
    trans = np.hypot(err[:, 0], err[:, 1])
    rot = np.abs(wrap_angle(err[:, 2]))
    # wrap_angle maps to [-pi, pi): a half turn is +-pi, its size pi either way
    if angle_unit == "deg":
        rot = np.degrees(rot)
    return RPEResult(
        int(delta), bool(all_pairs), pairs, trans, rot, angle_unit, i_ref, i_est, statistics(trans), statistics(rot)
    )


@dataclass(frozen=True)
class Evaluation:
    """ATE and RPE of one estimate against one reference (what ``omnikin metrics`` prints)."""

    ate: ATEResult
    rpe: RPEResult
    settings: dict = field(default_factory=dict)

    def as_dict(self) -> dict:
        return {"settings": dict(self.settings), "ate": self.ate.as_dict(), "rpe": self.rpe.as_dict()}


def evaluate(
    t_ref,
    ref,
    t_est,
    est,
    *,
    align: bool = False,
    delta: int = 1,
    all_pairs: bool = False,
    angle_unit: str = "rad",
    max_diff: float = 0.01,
    offset: float = 0.0,
) -> Evaluation:
    """:func:`ate` and :func:`rpe` with the same association."""
    a = ate(t_ref, ref, t_est, est, align=align, max_diff=max_diff, offset=offset)
    r = rpe(
        t_ref,
        ref,
        t_est,
        est,
        delta=delta,
        all_pairs=all_pairs,
        angle_unit=angle_unit,
        max_diff=max_diff,
        offset=offset,
    )
    settings = {
        "align": align,
        "delta": int(delta),
        "delta_unit": "frames",
        "all_pairs": all_pairs,
        "max_diff": max_diff,
        "offset": offset,
        "angle_unit": angle_unit,
    }
    return Evaluation(a, r, settings)
