"""Monte Carlo of full UMBmark procedures: target >= 10 million simulated robot-samples/s.

1000 procedures (5 cw + 5 ccw runs each) of tomasi-omni3 as built ('typical' errors and
noise) at 100 Hz by ``omnikin.evaluation.umbmark.simulate_umbmark``, against a reference measured
in the same run: the straightforward vectorised NumPy simulation of one run at a time
(wheel increments with slip noise, forward kinematics, the SE(2) exponential of every
sample, rotation into the world and cumulative sums), timed on 100 runs.
"""

from __future__ import annotations

import time

import numpy as np

from _common import save
from omnikin import load_robot
from omnikin.evaluation.umbmark import simulate_umbmark
from omnikin.motion.plans import umbmark_square
from omnikin.motion.timing import sample_plan
from omnikin.simulation.error_models import NOISE, PROFILES
from omnikin.simulation.kinematic import commanded_angles


def reference_run(true, nominal, sampled, noise, rng):
    """One noisy run, one trial, written the straightforward way."""
    wheels = [w for w in nominal.rolling if w.encoder is not None]
    angles, _ = commanded_angles(sampled, nominal, wheels)
    d = np.diff(angles, axis=0)
    r = np.array([w.radius for w in wheels])
    d = d + noise.slip * np.sqrt(np.abs(d) * r) / r * rng.standard_normal(d.shape)
    inc = d @ true.fk_matrix().T
    inc[:, 2] += noise.floor * np.sqrt(np.hypot(inc[:, 0], inc[:, 1])) * rng.standard_normal(len(inc))
    a, b, phi = inc.T
    small = np.abs(phi) < 1e-9
    safe = np.where(small, 1.0, phi)
    s1 = np.where(small, 1.0, np.sin(phi) / safe)
    c1 = np.where(small, 0.0, (1 - np.cos(phi)) / safe)
    dx, dy = s1 * a - c1 * b, c1 * a + s1 * b
    th = np.concatenate([[0.0], np.cumsum(phi)])
    c, s = np.cos(th[:-1]), np.sin(th[:-1])
    return np.array([np.sum(c * dx - s * dy), np.sum(s * dx + c * dy), th[-1]])


def main(procedures: int = 1000) -> dict:
    nominal = load_robot("tomasi-omni3")
    true = PROFILES["typical"].sample(nominal, 1).apply(nominal)
    noise = NOISE["typical"]
    samples_per_run = len(sample_plan(umbmark_square("cw"), nominal, 100.0).progress)
    t0 = time.perf_counter()
    results = simulate_umbmark(true, nominal, noise=noise, trials=procedures, rng=2)
    elapsed = time.perf_counter() - t0
    total = procedures * 10 * samples_per_run
    sampled = sample_plan(umbmark_square("cw"), nominal, 100.0)
    rng = np.random.default_rng(3)
    n_ref = 100
    t0 = time.perf_counter()
    for _ in range(n_ref):
        reference_run(true, nominal, sampled, noise, rng)
    ref_rate = n_ref * samples_per_run / (time.perf_counter() - t0)
    rate = total / elapsed
    e = np.array([r.e_max_syst for r in results])
    print(
        f"Monte Carlo UMBmark, tomasi-omni3, {procedures} procedures x 10 runs x {samples_per_run} samples "
        f"(100 Hz) = {total / 1e6:.1f} M robot-samples"
    )
    print(
        f"  omnikin run_umbmark          {elapsed:6.2f} s   {rate / 1e6:6.2f} M samples/s   "
        f"{rate / ref_rate:5.2f}x the reference"
    )
    print(f"  straightforward numpy (ref)             {ref_rate / 1e6:6.2f} M samples/s")
    print(
        f"  E_max,syst over procedures: median {np.median(e) * 1000:.1f} mm, 5-95 % "
        f"{np.percentile(e, 5) * 1000:.1f}-{np.percentile(e, 95) * 1000:.1f} mm"
    )
    print(f"  target >= 10 M samples/s: {'met' if rate >= 10e6 else 'NOT met'}")
    return {
        "procedures": procedures,
        "samples": total,
        "seconds": elapsed,
        "samples_per_s": rate,
        "reference_samples_per_s": ref_rate,
        "target": 10e6,
    }


if __name__ == "__main__":
    save("simulation", main())
