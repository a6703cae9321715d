"""Mobility analysis of a wheel layout (Campion, Bastin and d'Andrea-Novel 1996).

* ``C1*`` stacks the sliding rows of fixed wheels (``C1f``) and of centred
  steerable wheels (``C1s``). Castors, off-centred steerable wheels and Swedish
  wheels add none: they never restrict the body motion.
* The analysis is made at *generic admissible* steering angles: a generic twist
  ``eta`` in the null space of ``C1f`` is picked and every centred steerable wheel
  is aligned with the velocity of its contact point under ``eta``.
* degree of mobility ``delta_m = 3 - rank C1*``;
* degree of steerability ``delta_s = rank C1* - rank C1f``: the number of
  steering angles that move the instantaneous centre of rotation independently.
  It equals Campion's ``rank C1s`` whenever the steered wheels are not redundant,
  and gives the textbook answer 1 for a car whose two front wheels are coupled by
  an Ackermann linkage (Siegwart and Nourbakhsh 2004, sec. 3.3.2), where
  ``rank C1s`` alone would be 2.
* Campion types ``(delta_m, delta_s)``: (3,0) omnimobile, (2,0) differential,
  (2,1), (1,1) car-like, (1,2).

Conditioning: the wheel Jacobian acts on twists whose rotation is scaled by a
characteristic length ``L`` [m], ``(vx, vy, L omega)``, so all columns are m/s.
When ``J^T J`` has an isotropic translational block and no translation-rotation
coupling, ``L`` is chosen to make the whole matrix isotropic (condition number 1,
Angeles 2003); otherwise ``L`` is the RMS distance of the wheels from the origin.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..common.messages import digits_apart
from .linalg import null_space, rank
from .wheels import Wheel

CAMPION_NAMES = {
    (3, 0): "omnimobile",
    (2, 0): "differential-drive like",
    (2, 1): "one steered wheel, omnimobile translation (2,1)",
    (1, 1): "car-like",
    (1, 2): "two independent steering angles (1,2)",
}

CONDITION_WARNING = 10.0
"""Condition number above which a layout is reported as badly conditioned. Forward kinematics
solves ``J twist = omega``; a relative error ``e`` of the wheel speeds (encoder quantisation,
slip: about 1 %) gives a relative twist error of up to ``kappa * e`` (Golub and Van Loan, Matrix
Computations, sec. 2.6). ``kappa = 1`` is the isotropic optimum (Angeles 2003); at 10 the worst
direction is measured an order of magnitude worse than a well-designed base. Every shipped robot
stays below 5."""

_GENERIC = np.array([0.7548776662, 0.5698402910, 0.3247179572])
"""A fixed 'generic' direction (powers of the plastic-number reciprocal)."""


@dataclass(frozen=True)
class Configuration:
    """A generic admissible configuration: twist and centred steering angles."""

    twist: np.ndarray  # (3,)
    steer: np.ndarray  # (n_steerable,) [rad], relative to mounting
    constraints: np.ndarray  # (k, 3) rows of C1* at these angles
    admissible: np.ndarray  # (3, delta_m) null-space basis of C1*


@dataclass(frozen=True)
class Mobility:
    """Result of :func:`analyse` (see module docstring for the definitions)."""

    rank: int
    degree_of_mobility: int
    degree_of_steerability: int
    holonomic: bool
    condition_number: float
    characteristic_length: float
    isotropic: bool

    @property
    def well_conditioned(self) -> bool:
        """True unless the condition number exceeds :data:`CONDITION_WARNING`."""
        return bool(self.condition_number <= CONDITION_WARNING)

    @property
    def conditioning_warning(self) -> str | None:
        """One sentence for the user when the layout is badly conditioned, else None."""
        if self.well_conditioned:
            return None
        c = self.condition_number
        p = digits_apart(c, CONDITION_WARNING, 3)
        return (
            f"badly conditioned wheel layout: condition number {c:.{p}g} > {CONDITION_WARNING:g}, so a 1 % "
            f"error in the wheel speeds can become a {c:.3g} % error of the twist in its worst direction "
            f"(check drive_deg and roller_deg of the wheels)"
        )

    @property
    def campion_type(self) -> tuple[int, int]:
        return (self.degree_of_mobility, self.degree_of_steerability)

    @property
    def campion_name(self) -> str:
        return CAMPION_NAMES.get(self.campion_type, "degenerate (outside Campion's five types)")


def characteristic_length(wheels: Sequence[Wheel]) -> float:
    """RMS distance of the wheels' steering/hub points from the origin [m] (1 if all at it)."""
    d2 = [w.x * w.x + w.y * w.y for w in wheels]
    rms = float(np.sqrt(np.mean(d2))) if d2 else 0.0
    return rms if rms > 0.0 else 1.0


def generic_configuration(wheels: Sequence[Wheel]) -> Configuration:
    """Generic admissible configuration of a layout (see module docstring)."""
    length = characteristic_length(wheels)
    fixed = [w.sliding_row() for w in wheels if w.is_fixed]
    c1f = np.array(fixed).reshape(-1, 3)
    nf = null_space(c1f, 3)
    z = _GENERIC[: nf.shape[1]]
    eta = nf @ z if nf.shape[1] else np.zeros(3)
    eta = eta * np.array([1.0, 1.0, 1.0 / length])
    steer: list[float] = []
    rows = list(fixed)
    for w in wheels:
        if not w.is_steerable:
            continue
        # centred wheels follow the generic motion; off-centred ones never constrain it
        # and may point anywhere: give each a distinct generic angle
        angle = float(w.align(eta)[0]) if w.is_centred_steerable else 0.5 + 1.3 * len(steer)
        steer.append(angle)
        if w.is_centred_steerable:
            rows.append(w.sliding_row(angle))
    cstar = np.array(rows).reshape(-1, 3)
    return Configuration(eta, np.array(steer), cstar, null_space(cstar, 3))


def _scaled_condition(jac: np.ndarray, basis: np.ndarray, length: float) -> float:
    """Condition number of ``jac`` restricted to ``basis``, rotation scaled by ``length``."""
    d = np.diag([1.0, 1.0, 1.0 / length])
    # basis of the admissible subspace in scaled coordinates (vx, vy, L omega)
    scaled_basis = np.linalg.qr(np.linalg.inv(d) @ basis)[0] if basis.size else basis
    m = jac @ d @ scaled_basis
    if m.size == 0:
        return float("inf")
    s = np.linalg.svd(m, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else float("inf")


def _isotropy_length(jac: np.ndarray) -> float | None:
    """Length making ``J^T J`` isotropic, if the structure allows one (else None)."""
    g = jac.T @ jac
    a = g[0, 0]
    tol = 1e-9 * max(1.0, abs(a))
    structured = (
        abs(g[0, 0] - g[1, 1]) < tol
        and abs(g[0, 1]) < tol
        and abs(g[0, 2]) < tol * max(1.0, np.sqrt(abs(g[2, 2])))
        and abs(g[1, 2]) < tol * max(1.0, np.sqrt(abs(g[2, 2])))
    )
    if not structured or a <= 0 or g[2, 2] <= 0:
        return None
    return float(np.sqrt(g[2, 2] / a))


def analyse(wheels: Sequence[Wheel], config: Configuration | None = None) -> Mobility:
    """Rank, Campion type and conditioning of a wheel layout."""
    config = config or generic_configuration(wheels)
    fixed_rank = rank(np.array([w.sliding_row() for w in wheels if w.is_fixed]).reshape(-1, 3))
    star_rank = rank(config.constraints)
    rolling = [w for w in wheels if not w.is_castor]
    steer_of = dict(zip([w.name for w in wheels if w.is_steerable], config.steer, strict=True))
    jac = np.array([w.rolling_row(steer_of.get(w.name, 0.0)) for w in rolling]).reshape(-1, 3)
    delta_m = 3 - star_rank
    length = characteristic_length(wheels)
    if delta_m == 3 and jac.size:
        iso = _isotropy_length(jac)
        length = iso if iso is not None else length
    cond = _scaled_condition(jac, config.admissible, length)
    return Mobility(
        rank=rank(jac),
        degree_of_mobility=delta_m,
        degree_of_steerability=star_rank - fixed_rank,
        holonomic=delta_m == 3,
        condition_number=cond,
        characteristic_length=length,
        isotropic=bool(abs(cond - 1.0) < 1e-9),
    )
