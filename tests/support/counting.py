"""Counting instead of timing: tests of linear time that hold on a busy machine."""

from __future__ import annotations

import pytest


class CountedName(str):
    """A name (column, key, wheel) that counts the comparisons made with it, for tests of linear
    time that count instead of timing (a busy machine changes the time, not the count): a search
    of the whole list per name compares about n^2 / 2 names, a dict, set or Counter about n. Set
    ``counts, budget = [], limit`` before the work: beyond ``limit`` the test fails at once."""

    counts: list = []
    budget = 0  # fail at once beyond it: a quadratic search would take minutes to finish

    def __eq__(self, other):
        CountedName.counts.append(1)
        if len(CountedName.counts) > CountedName.budget:
            pytest.fail(f"more than {CountedName.budget} name comparisons: a search of the whole list per name")
        return str.__eq__(self, other)

    __hash__ = str.__hash__
