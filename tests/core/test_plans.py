"""Motion plans (omnikin.plans): bounds on what a plan may ask for."""

from __future__ import annotations

import pytest


@pytest.mark.parametrize("text", ["line 1e308", "line -1e6", "spin 1e9", "arc 1 1e9", "square cw rotate 1e6"])
def test_absurd_plan_lengths_are_refused_before_sampling(text):
    """A path no robot drives (a typo such as ``line 1e308``) is refused when the plan is made,
    naming the limit, instead of being fitted or sampled."""
    from omnikin.errors import InputError
    from omnikin.plans import MAX_SEGMENT, parse_plan

    with pytest.raises(InputError, match="length must be from 0 to 100000"):
        parse_plan(text)
    assert parse_plan("line 5").segments[0].length == 5.0 <= MAX_SEGMENT
