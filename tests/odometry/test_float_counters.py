"""Float readings of a counter with a declared width wrap exactly like integer readings.

The expected increments are computed here with Python integers (or fractions) from the very
floats fed to the odometry: ``(b - a + half) % full - half``, exact by construction, then
rounded once to a float; the poses are the closed form of tomasi-omni3
(``support.tomasi.tomasi_poses``). The same wrap taken in floats, ``(delta + half) % full - half``,
would lose every increment of a 64-bit counter (``delta + 2**63`` has no bits left for a few ticks).
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from omnikin import Odometry, batch_odometry, load_robot
from omnikin.odometry.counters import wrap_scalar
from support.tomasi import assert_poses_close, tomasi_poses


def exact_wrap(delta, bits):
    """Independent exact wrapping of a Python int or Fraction into [-2**(bits-1), 2**(bits-1))."""
    half, full = 2 ** (bits - 1), 2**bits
    return (delta + half) % full - half


def stream(robot, t, rows, **kw):
    o = Odometry(robot, **kw)
    return np.array([o.update(t[k], rows[k]) for k in range(len(t))], dtype=float)


def test_the_reported_64_bit_float_readings_move():
    """The tester's reproduction: 100 samples of (+4, -2, -2) ticks as floats on a 64-bit counter
    drive 0.1728 m along +y, as the same readings as integers do (before: the origin)."""
    r = load_robot("tomasi-omni3")
    t = np.arange(101) * 0.01
    tk = np.cumsum(np.tile([4, -2, -2], (101, 1)), 0)
    expected = tomasi_poses([[4, -2, -2]] * 100)
    assert expected[-1, 1] == pytest.approx(0.1728, abs=1e-4)
    assert_poses_close(batch_odometry(r, t, tk.astype(float), counter_bits=64).poses, expected, atol=1e-9)
    assert_poses_close(stream(r, t, tk.astype(float).tolist(), counter_bits=64), expected, atol=1e-9)


def float_counter_log(bits, seed, n=40):
    """Float readings of a ``bits``-bit counter that wraps during the log, stored signed or
    unsigned at random (every float in ``[-2**(bits-1), 2**bits)``), and the exact wrapped
    increments of those floats (Python ints: every such float is a whole number here)."""
    rng = np.random.default_rng(seed)
    half, full = 2 ** (bits - 1), 2**bits
    step = max(1, min(half // 4, 3000))
    true = rng.integers(-step, step + 1, size=(n, 3)).tolist()
    start = [(full - 5 * step) % full, (7 * step) % full, (half - 3 * step) % full]  # wraps within the log
    rows, counts = [], list(start)
    for k in range(n + 1):
        row = []
        for j in range(3):
            stored = counts[j] - full if (k + j) % 2 and counts[j] >= half else counts[j]
            value = float(stored)
            if value >= full:  # rounded up beyond the counter: the signed form of the same count
                value = float(stored - full)
            row.append(value)
        rows.append(row)
        if k < n:
            counts = [(c + d) % full for c, d in zip(counts, true[k], strict=True)]
    increments = [
        [exact_wrap(int(b) - int(a), bits) for a, b in zip(r0, r1, strict=True)]
        for r0, r1 in zip(rows[:-1], rows[1:], strict=True)
    ]
    return rows, increments


@pytest.mark.parametrize("bits", range(2, 65))
def test_float_readings_of_every_width_wrap_like_exact_integers(tomasi, bits):
    """Widths 2..64, batch and streaming: the poses are the closed form of the exactly wrapped
    increments of the float readings (beyond 2**53 the floats are coarse, and their exact
    differences are what counts). One sample per second, so that the increments of up to
    a few thousand ticks (wider counters read as floats move in steps of up to 2048) stay
    within the speed and change-of-speed bounds."""
    rows, increments = float_counter_log(bits, seed=bits)
    raw = np.diff(np.array(rows, dtype=object), axis=0)
    assert np.any(np.abs(raw) >= 2 ** (bits - 1)), "the log must wrap"
    t = [float(k) for k in range(len(rows))]
    expected = tomasi_poses(increments)
    assert_poses_close(batch_odometry(tomasi, t, np.array(rows), counter_bits=bits).poses, expected, atol=1e-7)
    assert_poses_close(stream(tomasi, t, rows, counter_bits=bits), expected, atol=1e-7)


@pytest.mark.parametrize("bits", [12, 32, 52, 53, 60, 64])
def test_fractional_float_readings_wrap_exactly(tomasi, bits):
    """Readings with fractions (an unquantised simulation): each increment is the exact
    wrapped difference of the two floats (fractions.Fraction), rounded once."""
    full, half = 2**bits, 2 ** (bits - 1)
    rng = np.random.default_rng(bits)
    base = float(full) * (1 - 2.0**-20) if bits > 20 else full - 37.25
    rows = [[base, 0.5, -0.75]]
    for _ in range(12):
        step = rng.uniform(-40, 40, size=3)
        nxt = [(v + s) for v, s in zip(rows[-1], step, strict=True)]
        rows.append([v - full if v >= full else (v + full if v < -half else v) for v in nxt])
    increments = [
        [float(exact_wrap(Fraction(b) - Fraction(a), bits)) for a, b in zip(r0, r1, strict=True)]
        for r0, r1 in zip(rows[:-1], rows[1:], strict=True)
    ]
    assert max(abs(v) for inc in increments for v in inc) < 64
    t = [0.1 * k for k in range(len(rows))]
    expected = tomasi_poses(increments)
    assert_poses_close(batch_odometry(tomasi, t, np.array(rows), counter_bits=bits).poses, expected, atol=1e-9)
    assert_poses_close(stream(tomasi, t, rows, counter_bits=bits), expected, atol=1e-9)


@pytest.mark.parametrize("bits", [2, 8, 16, 32, 53, 63, 64])
def test_wrap_scalar_of_a_float_is_exact(bits):
    """wrap_scalar (also used by the serial link) of a float: the exact wrapped value, rounded once."""
    rng = np.random.default_rng(bits)
    for v in np.concatenate([rng.uniform(-(2.0**bits), 2.0**bits, 200), [2.0 ** (bits - 1) - 1, -(2.0**bits) + 3]]):
        got = wrap_scalar(float(v), bits)
        assert got == float(exact_wrap(Fraction(float(v)), bits)), (v, got)
        assert -(2.0 ** (bits - 1)) <= got <= 2.0 ** (bits - 1)
    assert wrap_scalar(5.0, 64) == 5.0 and wrap_scalar(-(2.0**64) + 4096, 64) == 4096.0
