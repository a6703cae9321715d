"""Motion plans (omnikin.motion.plans): bounds on what a plan may ask for."""

from __future__ import annotations

import math

import pytest


@pytest.mark.parametrize("text", ["line 1e308", "line -1e6", "arc 10000 720", "square cw rotate 1e6"])
def test_absurd_plan_lengths_are_refused_before_sampling(text):
    """A path no robot drives (a typo such as ``line 1e308``) is refused when the plan is made,
    naming the limit, instead of being fitted or sampled."""
    from omnikin.errors import InputError
    from omnikin.motion.plans import MAX_SEGMENT, parse_plan

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
    """parse_plan, called from Python (and by omnikin.simulate), reads its numbers as files and
    --path do, not with float() ('line 1_0' is no 10 m line, Arabic-Indic digits are no numbers):
    one line naming the path and what is wrong with the word."""
    from omnikin.errors import InputError
    from omnikin.motion.plans import parse_plan

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
    from omnikin.motion.plans import parse_plan

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
    from omnikin.motion.plans import parse_plan

    with pytest.raises(InputError) as info:
        parse_plan(text)
    assert contains in str(info.value) and "\n" not in str(info.value) and len(str(info.value)) < 400


# --- angles of paths ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("text", ["line 4 1e300", "line 4 -1e300", "line 4 720.001", "line 4 -1000"])
def test_a_heading_is_a_direction_within_two_turns_like_a_robot_files(text):
    """A heading is a direction: within +-720 deg, the bound of a robot file's
    angle_deg/drive_deg ('line 4 1e300' would be whatever direction 1e300 deg rounds to)."""
    from omnikin.errors import InputError
    from omnikin.io.robot_file import FIELD_RANGES
    from omnikin.motion.plans import parse_plan

    assert FIELD_RANGES["angle_deg"][:2] == FIELD_RANGES["drive_deg"][:2] == (-720.0, 720.0)
    with pytest.raises(InputError, match=rf"^path {text!r}: heading must lie in \[-720, 720\] deg, got "):
        parse_plan(text)


def test_headings_of_two_turns_either_way_are_directions():
    """720 deg and -630 deg are the directions 0 and 90 deg."""
    from omnikin.motion.plans import parse_plan

    for text, deg in (("line 4 720", 0.0), ("line 4 -630", 90.0), ("line 4 -720", 0.0)):
        (seg,) = parse_plan(text).segments
        assert seg.xi[:2] == pytest.approx((math.cos(math.radians(deg)), math.sin(math.radians(deg))), abs=1e-12)


@pytest.mark.parametrize("text", ["spin 1e9", "spin -5.73e6", "arc 1 1e9", "arc 0.001 -1e7"])
def test_a_turn_is_refused_in_the_degrees_it_was_written_in(text):
    """'spin 1e9' said 'length must be from 0 to 100000 [m or rad], got 1.7e7' (radians, while
    the path is in degrees). The longest turn is 1e5 rad = 5729577.95 deg."""
    from omnikin.errors import InputError
    from omnikin.motion.plans import parse_plan

    pattern = rf"^path {text!r}: angle must lie in \[-5729577.95\d*, 5729577.95\d*\] deg, got \S+ \(the longest"
    with pytest.raises(InputError, match=pattern) as info:
        parse_plan(text)
    assert "rad, got" not in str(info.value)
    assert parse_plan("spin 5.7e6").segments[0].length == pytest.approx(math.radians(5.7e6))


@pytest.mark.parametrize("radius", ["1e-320", "4e-324", "0", "-1"])
def test_an_arc_without_a_finite_curvature_names_the_path(radius):
    """'arc 1e-320 90' failed with 'segment: xi must be a finite non-zero twist' (1/1e-320 is
    inf), without the path."""
    from omnikin.errors import InputError
    from omnikin.motion.plans import parse_plan

    text = f"arc {radius} 90"
    with pytest.raises(InputError, match=rf"^path {text!r}: arc radius must be > 0 with a finite curvature"):
        parse_plan(text)


@pytest.mark.parametrize("blank", ["\x1c", "\x1f", "\u3000", "\u00a0", "\u2003", "\n", "\r", "\x0b", "\x85"])
def test_words_of_a_path_are_separated_by_ascii_blanks_only(blank):
    """Words are separated by spaces and tabs; any other white space (U+001C, U+3000, which
    str.split() splits at) is refused, naming its code point."""
    from omnikin.errors import InputError
    from omnikin.motion.plans import parse_plan

    text = f"line{blank}4"
    with pytest.raises(InputError, match=rf"^path .*: white space U\+{ord(blank):04X}\b.*separate the words"):
        parse_plan(text)
    assert parse_plan("line \t 4  \t90").segments[0].length == 4.0


def test_python_builders_bound_their_angles_in_radians():
    from omnikin.errors import InputError
    from omnikin.motion.plans import arc, line

    with pytest.raises(InputError, match=r"line heading must lie in \[-12.566\d*, 12.566\d*\] rad"):
        line(1.0, 1e300)
    with pytest.raises(InputError, match=r"arc angle must lie in \[-100000, 100000\] rad"):
        arc(1.0, 2e5)
    with pytest.raises(InputError, match=r"arc radius must be > 0 with a finite curvature"):
        arc(1e-320, 1.0)
