"""The one check that refuses a job before it starts (omnikin.common.resource_limits): the command line
(--max-memory, --max-time) and the Python entry points (max_memory, max_time) refuse the same
job with the same line, sizes in the same unit style, only the names of the limits differ (not
'... more than --max-memory 2G' from one and '... more than max_memory 2 GiB' from the other),
and a limit that is no number (max_memory='2G') is refused in one line, not with a TypeError."""

from __future__ import annotations

import math
import re

import pytest

from omnikin.common.resource_limits import LimitNames, format_bytes, format_seconds, require_within
from omnikin.errors import InputError, ResourceLimitError
from support.cli import run_cli

OPTIONS = LimitNames("--max-memory", "--max-time")
ARGUMENTS = LimitNames("max_memory", "max_time")


@pytest.mark.parametrize("names", [OPTIONS, ARGUMENTS], ids=["options", "arguments"])
def test_one_line_names_the_estimate_the_limit_and_the_way_out(names):
    """3 GiB against the default 2 GiB; 5400 s (1.5 h) against 3600 s (1 h)."""
    m, t = names.memory, names.time
    with pytest.raises(ResourceLimitError) as info:
        require_within("job", memory=3 * 1024**3, seconds=1.0, size="7 things", hint="do less", names=names)
    assert str(info.value) == f"job: about 3G of memory for 7 things, more than {m} 2G; do less, or raise {m}"
    assert (info.value.needed, info.value.limit, info.value.unit) == (3 * 1024**3, 2 * 1024**3, "bytes")
    with pytest.raises(ResourceLimitError) as info:
        require_within("job", memory=1024, seconds=5400.0, hint="do less", names=names)
    assert str(info.value) == f"job: about 1.5 h, more than {t} 1 h; do less, or raise {t}"
    assert (info.value.needed, info.value.limit, info.value.unit) == (5400.0, 3600.0, "seconds")
    require_within("job", memory=2 * 1024**3, seconds=3600.0, hint="do less", names=names)  # at the limits: fine


def test_sizes_and_durations_are_written_one_way():
    assert [format_bytes(n) for n in (2 * 1024**3, 1.5 * 1024**3, 300 * 1024**2, 12 * 1024, 100)] == [
        "2G",
        "1.5G",
        "300M",
        "12K",
        "100 bytes",
    ]
    assert [format_seconds(s) for s in (45, 720, 12600, 40 * 86400, math.inf)] == [
        "45 s",
        "12 min",
        "3.5 h",
        "40 days",
        "inf",
    ]


@pytest.mark.parametrize("limit", ["2G", -1, 0, math.nan, True, None, 1 + 0j])
@pytest.mark.parametrize("which", ["max_memory", "max_time"])
def test_a_limit_that_is_no_limit_is_named(which, limit):
    with pytest.raises(InputError) as info:
        require_within("job", memory=1.0, seconds=1.0, hint="-", names=ARGUMENTS, **{which: limit})
    assert str(info.value).startswith(f"{which} must be a number of ") and "\n" not in str(info.value)


@pytest.mark.parametrize("which", ["max_memory", "max_time"])
def test_an_integer_below_every_float_is_a_negative_limit_not_none(which):
    """-10**400 is beyond floats: its sign decides (a negative limit, refused), not float()'s
    +inf (no limit at all)."""
    with pytest.raises(InputError, match=rf"^{which} must be a number of .* > 0") as info:
        require_within("job", memory=1.0, seconds=1.0, hint="-", names=ARGUMENTS, **{which: -(10**400)})
    assert "\n" not in str(info.value) and len(str(info.value)) < 200
    require_within("job", memory=1.0, seconds=1.0, hint="-", names=ARGUMENTS, **{which: 10**400})  # no limit


def test_an_infinite_limit_is_no_limit():
    require_within("job", memory=1e30, seconds=1e30, max_memory=math.inf, max_time=math.inf, hint="-", names=OPTIONS)


def test_command_line_and_python_refuse_a_study_alike(capsys):
    """The same study of 1e9 trials, refused by 'omnikin umbmark' and by omnikin.run_umbmark: the
    same estimate and the same limit, 2G, each named its own way."""
    import omnikin

    rc, out, err = run_cli(capsys, "umbmark", "diff-drive", "--trials", "1000000000")
    assert rc == 2 and out == "" and err.count("\n") == 1, err
    with pytest.raises(ResourceLimitError) as info:
        omnikin.run_umbmark("diff-drive", trials=10**9)
    pattern = r"about (\S+) of memory for (\S+) robot-samples, more than (\S+) (\S+); .*, or raise (\S+)$"
    cli, api = re.search(pattern, err.strip()), re.search(pattern, str(info.value))
    assert cli and api, (err, str(info.value))
    assert cli.group(1, 2, 4) == api.group(1, 2, 4) and cli.group(4) == "2G"
    assert cli.group(3, 5) == ("--max-memory", "--max-memory") and api.group(3, 5) == ("max_memory", "max_memory")


def test_python_refuses_a_limit_that_is_no_number_in_one_line():
    import omnikin

    with pytest.raises(InputError, match=r"^max_memory must be a number of bytes > 0 \(inf: no limit\), got '2G'$"):
        omnikin.run_umbmark("diff-drive", max_memory="2G")
