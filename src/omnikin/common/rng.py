"""Random number generators: every random function of omnikin takes ``rng`` (no global state)."""

from __future__ import annotations

import numpy as np

from ..errors import InputError


def make_rng(rng) -> np.random.Generator:
    """A Generator from ``rng``: a Generator is used as is; a seed (or None) seeds SFC64,
    whose normal variates cost about a quarter less than the default PCG64's."""
    if isinstance(rng, np.random.Generator):
        return rng
    if isinstance(rng, np.random.SeedSequence) or rng is None or isinstance(rng, (int, np.integer)):
        return np.random.Generator(np.random.SFC64(rng))
    raise InputError(f"rng must be a numpy Generator, a SeedSequence, an integer seed or None, got {rng!r}")
