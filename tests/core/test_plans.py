"""Motion plans (omnikin.plans): bounds on what a plan may ask for."""

from __future__ import annotations

import math

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


HOSTILE = ["nan", "-inf", "Infinity", "1_0", "\u0661", "\uff11", "\u00b2", "0x10", "1e999", "1e", "+-1", "1.2.3"]
"""Spellings Python's float() reads, or half reads: not-a-number and infinities, digit groups,
Arabic-Indic and full-width digits, a superscript, hexadecimal, an overflow, broken forms."""


@pytest.mark.parametrize("word", HOSTILE)
@pytest.mark.parametrize(
    "template", ["line {}", "line 1 {}", "spin {}", "arc 1 {}", "arc {} 90", "square cw rotate {}"]
)
def test_a_path_from_python_takes_plain_numbers_only(template, word):
    """parse_plan, called from Python (and by omnikin.simulate), read its numbers with float():
    'line 1_0' was a 10 m line, Arabic-Indic digits were numbers. It now reads them as files and
    --path do: one line naming the path and what is wrong with the word."""
    from omnikin.errors import InputError
    from omnikin.plans import parse_plan

    text = template.format(word)
    with pytest.raises(InputError) as info:
        parse_plan(text)
    message = str(info.value)
    assert message.startswith(f"path {text!r}: ") and "\n" not in message, message
    assert any(p in message for p in ("not a number: ", "non-finite value ", "is too large")), message


def test_python_entry_points_refuse_a_hostile_path():
    import omnikin

    with pytest.raises(omnikin.InputError, match=r"^path 'line 1_0': not a number: '1_0'"):
        omnikin.simulate("tomasi-omni3", "line 1_0")


def test_plain_spellings_of_a_path_are_read_exactly():
    """'+.5' is 0.5 m; '-2.5E+1' is -25 deg: the unit direction (cos, sin) of -25 deg."""
    from omnikin.plans import parse_plan

    (seg,) = parse_plan("LINE +.5 -2.5E+1").segments
    h = math.radians(-25.0)
    assert seg.length == 0.5 and seg.xi == (math.cos(h), math.sin(h), 0.0)
    assert parse_plan("square ccw translate 2.").segments[0].length == 2.0
    assert [s.length for s in parse_plan("spin 90").segments] == [math.pi / 2]


@pytest.mark.parametrize(
    "text, contains",
    [
        ("hop 3", "unknown kind of path 'hop'"),
        ("square up rotate", "unknown UMBmark direction 'up'"),
        ("square cw " + "x" * 10_000, "unknown path mode 'xxxx"),
        ("line", "expected 'square cw|ccw"),
        (None, "path must be text"),
    ],
    ids=["unknown kind", "unknown direction", "long mode", "too few words", "not text"],
)
def test_bad_paths_are_named_in_one_bounded_line(text, contains):
    from omnikin.errors import InputError
    from omnikin.plans import parse_plan

    with pytest.raises(InputError) as info:
        parse_plan(text)
    assert contains in str(info.value) and "\n" not in str(info.value) and len(str(info.value)) < 400
