"""The command line as a hostile user meets it: every error one line, never a traceback;
negative numbers are values; unknown names get a suggestion.

One-line means: stderr holds exactly ``omnikin: error: ...`` (bounded, no newline inside),
stdout nothing, status 2 for bad input or usage.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from omnikin.cli.main import main
from omnikin.cli.process import MESSAGE_LIMIT
from support.cli import run_cli as cli
from support.cli import run_entry_point
from support.paths import omnikin_env

TOMASI_J = np.array([[-math.sin(b), math.cos(b), 0.113] for b in np.radians([0.0, 120.0, 240.0])]) / 0.04125
# omni4 (preset file): hubs at 45 + 90 k deg on a 0.2 m circle, drive = counter-clockwise tangent, r = 0.05
OMNI4_J = np.array([[-math.sin(b), math.cos(b), 0.2] for b in np.radians([45.0, 135.0, 225.0, 315.0])]) / 0.05


def one_line(rc, out, err, *fragments, status=2):
    assert rc == status, err
    assert out == ""
    assert err.endswith("\n") and err.count("\n") == 1, err
    assert err.startswith("omnikin: error: ") and "Traceback" not in err
    for f in fragments:
        assert f in err, (f, err)
    return err.strip()


entry_point = run_entry_point


# --- negative numbers are values ------------------------------------------------------------------------
def test_negative_exponent_twist_is_a_value(capsys):
    rc, out, err = cli(capsys, "ik", "tomasi-omni3", "-2.5e-3", "0", "0", "--json")
    assert rc == 0, err
    data = json.loads(out)
    assert data["twist"] == [-2.5e-3, 0.0, 0.0]
    np.testing.assert_allclose(data["wheel_speeds"], TOMASI_J @ [-2.5e-3, 0, 0], atol=1e-15)


def test_all_negative_wheel_speeds_are_values(capsys):
    rc, out, err = cli(capsys, "fk", "omni4", "-1", "-2", "-3", "-4", "--json")
    assert rc == 0, err
    twist, *_ = np.linalg.lstsq(OMNI4_J, [-1.0, -2.0, -3.0, -4.0], rcond=None)
    np.testing.assert_allclose(json.loads(out)["twist"], twist, atol=1e-12)


def test_negative_option_values_in_exponent_notation(capsys):
    """--steer-deg takes several values, all negative; synchro's wheels steered to -10 deg rolling at
    4 rad/s (r = 0.05 m) translate at 0.2 m/s along -10 deg."""
    rc, out, err = cli(capsys, "fk", "synchro", "4", "4", "4", "--steer-deg", "-1e1", "-1E1", "-10", "--json")
    assert rc == 0, err
    a = math.radians(-10)
    np.testing.assert_allclose(json.loads(out)["twist"], [0.2 * math.cos(a), 0.2 * math.sin(a), 0], atol=1e-12)
    rc, out, err = cli(capsys, "ik", "tomasi-omni3", "1", "0", "0", "--heading", "-1.5e0", "--json")
    assert rc == 0, err
    h = -1.5  # world (1, 0) seen from a body at heading h
    np.testing.assert_allclose(json.loads(out)["twist"], [math.cos(h), -math.sin(h), 0], atol=1e-12)


def test_negative_infinity_is_a_value_refused_as_not_finite(capsys):
    """'-inf' is read as a value (not an option) and refused as one, naming the argument."""
    one_line(*cli(capsys, "ik", "tomasi-omni3", "-inf", "0", "0"), "argument VX", "non-finite value '-inf'")


def test_string_values_keep_their_spelling(capsys):
    """A robot named like a negative number is looked up as typed, not with argparse's workaround."""
    line = one_line(*cli(capsys, "show", "-1e3"))
    assert "-1e3" in line and "no such robot file" in line and " -1e3" not in line.split("error: ")[1]


def test_double_dash_still_works(capsys):
    rc, out, err = cli(capsys, "ik", "tomasi-omni3", "--json", "--", "-2e-3", "0", "0")
    assert rc == 0 and json.loads(out)["twist"] == [-2e-3, 0.0, 0.0]


def _value_options():
    """``(command words, option and values)`` for every option of every command that takes a
    converted value, with the value ``-1q`` (as many as the option takes)."""
    import argparse

    from omnikin.cli.main import build_parser

    found = []

    def walk(parser, words):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    walk(sub, [*words, name])
            elif action.option_strings and action.type is not None and action.nargs != 0:
                count = action.nargs if isinstance(action.nargs, int) else 1
                found.append((words, [action.option_strings[-1]] + ["-1q"] * count))
        for name, sub in getattr(parser, "_commands", {}).items():
            walk(sub, [*words, name])

    walk(build_parser(), [])
    return found


@pytest.mark.parametrize("words, option", _value_options(), ids=lambda v: " ".join(v))
def test_a_negative_value_is_quoted_as_typed_for_every_option(capsys, words, option):
    """'--max-time -1' said "' -1' is not a duration": the mark that makes argparse take -1 as a
    value showed in the message, for every option type."""
    rc, out, err = cli(capsys, *words, *option)
    assert rc == 2 and err.count("\n") == 1, err
    assert "'-1q'" in err and "' -1q'" not in err, err


@pytest.mark.parametrize(
    "value, message",
    [
        ("-1", "'-1': a duration must be positive"),
        ("-2h", "'-2h': a duration must be positive"),
        ("1e400", "'1e400' is too large for a duration"),
        ("1e999h", "'1e999h' is too large for a duration"),
    ],
)
def test_durations_say_what_is_wrong(capsys, value, message):
    one_line(*cli(capsys, "umbmark", "--max-time", value), f"argument --max-time: {message}")


@pytest.mark.parametrize(
    "value, message",
    [
        ("-5M", "'-5M': a size must be at least one byte"),
        ("0.5", "'0.5': a size must be at least one byte"),
        ("1e999", "'1e999' is too large for a size"),
    ],
)
def test_sizes_say_what_is_wrong(capsys, value, message):
    one_line(*cli(capsys, "simulate", "tomasi-omni3", "--max-memory", value), f"argument --max-memory: {message}")


def test_messages_speak_command_line_not_python(capsys):
    """simulate --path 'square cw translate 4' on a differential drive suggested the Python
    argument on_infeasible='return' to a command-line user."""
    line = one_line(
        *cli(capsys, "simulate", "diff-drive", "--path", "square cw translate 4", "--log", "-"),
        "--path 'square cw translate 4'",
        "fixed wheel 'left' would slide sideways",
    )
    assert "on_infeasible" not in line and "=" not in line
    line = one_line(*cli(capsys, "ik", "diff-drive", "0", "1", "0"), "--allow-infeasible")
    assert "on_infeasible" not in line


def test_rounding_noise_prints_as_zero_and_json_keeps_the_numbers(capsys):
    """'ik tomasi-omni3 -1 0 0' printed w1 -1.48442e-15: w1 (hub at 0 deg) drives along +y, so a
    pure -x motion leaves it still; the others turn at -/+ sin(120 deg) / r."""
    rc, out, err = cli(capsys, "ik", "tomasi-omni3", "-1", "0", "0")
    assert rc == 0, err
    rows = {
        line.split()[1]: line.split()[3] for line in out.splitlines() if line.split()[1:2] in (["w1"], ["w2"], ["w3"])
    }
    speed = math.sin(math.radians(120)) / 0.04125
    assert rows["w1"] == "0" and float(rows["w2"]) == pytest.approx(speed, rel=1e-5)
    assert float(rows["w3"]) == pytest.approx(-speed, rel=1e-5)
    rc, out, err = cli(capsys, "ik", "tomasi-omni3", "-1", "0", "0", "--json")
    np.testing.assert_allclose(json.loads(out)["wheel_speeds"], TOMASI_J @ [-1, 0, 0], atol=1e-12)
    rc, out, err = cli(capsys, "fk", "tomasi-omni3", "0", str(speed), str(-speed))
    assert rc == 0 and out.splitlines() == [
        "tomasi-omni3: vx=-1 m/s, vy=0 m/s, omega=0 rad/s",
        "residual [rad/s]: [0.0, 0.0, 0.0] (norm 0)",
    ], out


# --- did you mean ----------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "argv, suggestion",
    [
        (["shwo", "omni4"], "'show'"),
        (["bag", "exprt", "x.bag"], "'export'"),
        (["ik", "tomasi-omni3", "0", "0", "0", "--jsn"], "'--json'"),
        (["fk", "omni4", "1", "2", "3", "4", "--steer-dg", "0"], "'--steer-deg'"),
        (["show", "tomasi-omni"], "'tomasi-omni3'"),
        (["ik", "mecanum", "0", "0", "0"], "'mecanum4'"),
    ],
)
def test_unknown_names_get_a_suggestion(capsys, argv, suggestion):
    line = one_line(*cli(capsys, *argv), "did you mean", suggestion)
    assert line.count("did you mean") == 1


def test_no_suggestion_when_nothing_is_close(capsys):
    line = one_line(*cli(capsys, "zzzzzz"), "unknown command 'zzzzzz'", "presets")
    assert "did you mean" not in line


def test_usage_errors_are_one_line_and_point_to_help(capsys):
    one_line(
        *cli(capsys, "ik", "tomasi-omni3", "zero", "0", "0"), "argument VX: not a number: 'zero'", "omnikin ik --help"
    )
    one_line(*cli(capsys, "ik"), "required", "ROBOT")
    one_line(*cli(capsys, "ik", "tomasi-omni3", "0", "0", "0", "7"), "unexpected argument '7'")
    one_line(*cli(capsys, "bag", "odometry", "tomasi-omni3"), "omnikin bag odometry --help")


def test_umbmark_analyze_is_a_command_of_umbmark(capsys):
    one_line(*cli(capsys, "umbmark", "analyze"), "umbmark analyze", "MEASUREMENTS.csv")
    assert main(["umbmark", "analyze", "--help"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: omnikin umbmark analyze") and "--side" in out


def test_umbmark_analyze_help_subprocess():
    proc = entry_point("umbmark", "analyze", "--help")
    assert proc.returncode == 0 and proc.stdout.startswith("usage: omnikin umbmark analyze")


# --- one line, whatever the library said ----------------------------------------------------------------------
def test_invalid_bag_metadata_is_one_line(tmp_path):
    """rosbags explains a YAML error over several lines; the user sees one, naming the bag."""
    pytest.importorskip("rosbags")
    bag = tmp_path / "bad.bag"
    bag.mkdir()
    (bag / "metadata.yaml").write_text("rosbag2_bagfile_information:\n  version: 8\n   storage: [\n")
    for argv in (
        ["bag", "export", bag, "--topic", "/odom", "--format", "tum"],
        ["bag", "odometry", "tomasi-omni3", bag, "-o", tmp_path / "o.bag"],
    ):
        proc = entry_point(*argv)
        one_line(proc.returncode, proc.stdout, proc.stderr, str(bag), "line 3")


def test_messages_are_flattened_and_bounded(capsys, tmp_path):
    """A robot path with a newline and one of 5000 characters: the error stays one bounded line."""
    one_line(*cli(capsys, "show", "first\nsecond"), "first", "second")
    line = one_line(*cli(capsys, "show", "x" * 5000))
    assert len(line) <= len("omnikin: error: ") + MESSAGE_LIMIT and "chars)" in line


@pytest.mark.parametrize(
    "argv",
    [
        ["ik", "tomasi-omni3", "1e308", "0", "0"],
        ["ik", "omni4", "1e308", "1e308", "1e308"],
        ["fk", "tomasi-omni3", "1e308", "1e308", "1e308"],
        ["fk", "omni4", "1e308", "-1e308", "1e308", "-1e308"],
    ],
)
def test_huge_inputs_give_finite_numbers_or_one_line(capsys, argv):
    """1e308 is a finite input whose results may overflow: the output is finite strict JSON, or
    the command ends with lines all starting 'omnikin: ' and an error last (a NumPy warning may
    precede it); never 'Infinity' in JSON, 'inf' in a table or a traceback."""
    for extra in (["--json"], []):
        rc, out, err = cli(capsys, *argv, *extra)
        assert "Traceback" not in err
        if rc == 0:
            if extra:
                json.loads(out, parse_constant=lambda c: pytest.fail(f"{c} in JSON"))
            else:
                assert "inf" not in out and "nan" not in out
            continue
        assert rc == 2 and out == ""
        lines = err.strip().splitlines()
        assert all(line.startswith("omnikin: ") for line in lines) and lines[-1].startswith("omnikin: error: ")


def test_closed_pipe_ends_quietly(tmp_path):
    """The reader of standard output stops early: no traceback, no 'Exception ignored' (some kernels
    hold the whole output in the pipe, then the command simply succeeds)."""
    pytest.importorskip("rosbags")
    bag = tmp_path / "long.bag"
    assert main(["simulate", "mecanum4", "--path", "line 10", "--rate", "1000", "--bag", str(bag)]) == 0
    env = omnikin_env()
    proc = subprocess.Popen(
        [sys.executable, "-m", "omnikin.cli.main", "bag", "export", str(bag), "--topic", "/odom", "--format", "tum"],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    proc.stdout.read(100)
    proc.stdout.close()
    err = proc.stderr.read()
    assert proc.wait(timeout=120) in (0, 141)
    assert "Traceback" not in err and "Exception" not in err and err.count("\n") <= 1


def test_floating_point_trouble_in_omnikin_is_an_error_not_a_wrong_number(capsys, tmp_path):
    """Positions of +-1e308 m are finite, their differences are not: the metrics would be inf or
    NaN. NumPy's warning inside omnikin's own computation ends the command with one line."""
    a, b = tmp_path / "a.tum", tmp_path / "b.tum"
    a.write_text("".join(f"{k} 1e308 0 0 0 0 0 1\n" for k in range(3)))
    b.write_text("".join(f"{k} -1e308 0 0 0 0 0 1\n" for k in range(3)))
    for extra in ([], ["--json"], ["--align"]):
        rc, out, err = cli(capsys, "metrics", a, b, *extra)
        assert rc == 2 and out == "" and "Traceback" not in err
        lines = err.strip().splitlines()
        assert all(line.startswith("omnikin: ") for line in lines)
        assert lines[-1].startswith("omnikin: error: numerical failure")


# --- sample rates of simulations ------------------------------------------------------------------------
@pytest.mark.parametrize("rate", ["1e-9", "4.99", "0", "-5", "nan", "inf", "10000.5", "1e9", "1e300"])
def test_simulate_refuses_a_rate_outside_5_hz_to_10_khz_like_umbmark(capsys, tmp_path, rate):
    """A rate outside 5 Hz .. 10 kHz ('--rate 1e-9' would be a run of one sample: noise of the
    sampling, not odometry): both commands and the Python entry points refuse the same rates, in
    one line naming the option and the range."""
    log = tmp_path / "log.csv"
    for command in (["simulate", "tomasi-omni3", "--log", log], ["umbmark", "-o", tmp_path / "r"]):
        rc, out, err = cli(capsys, *command, "--rate", rate)
        # a number outside the range names the range; nan and inf are not numbers of the CLI at all
        one_line(rc, out, err, "--rate", "[5, 10000] Hz" if rate not in ("nan", "inf") else "non-finite")
    assert list(tmp_path.iterdir()) == []
    import omnikin

    with pytest.raises(omnikin.InputError, match=r"^rate: the sample rate .*\[5, 10000\] Hz") as info:
        omnikin.simulate("tomasi-omni3", "spin 10", rate=float(rate))
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("rate", ["5", "10000"])
def test_simulate_takes_the_ends_of_the_rate_range(capsys, rate):
    """The ends are in the range. 'line 0.3' at the default 0.3 m/s and 0.5 m/s^2 is a
    trapezoid of 0.6 s ramps and 0.4 s cruise: 1.6 s, i.e. 1.6 * rate intervals, plus one sample."""
    rc, out, err = cli(capsys, "simulate", "tomasi-omni3", "--path", "line 0.3", "--rate", rate, "--log", "-")
    assert rc == 0, err
    rows = [line for line in out.splitlines() if line and not line.startswith("#")]
    assert len(rows) - 1 == round(1.6 * float(rate)) + 1  # header, then one row per sample


@pytest.mark.parametrize("text", ["1_0", "\u0661", " 1", "0x1", "nan", "inf", "1e999", "", "1,5"])
@pytest.mark.parametrize(
    "argv",
    [
        ("ik", "tomasi-omni3", "{}", "0", "0"),
        ("fk", "tomasi-omni3", "{}", "0", "0"),
        ("umbmark", "--side", "{}"),
    ],
)
def test_number_options_take_plain_finite_decimals_only(capsys, argv, text):
    """Every number on the command line follows the one grammar of numbers read from text
    (omnikin.common.number_text): Python's float() would read 1_0, non-ASCII digits, blanks, nan, inf."""
    rc, _, err = cli(capsys, *[a.format(text) for a in argv])
    assert rc == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("omnikin: error:")
    assert "not a number" in lines[0] or "non-finite" in lines[0] or "too large" in lines[0]


@pytest.mark.parametrize("text", ["1_0", "\u0661", "0x5", "5.0", " 5", ""])
def test_whole_number_options_take_ascii_digits_only(capsys, text):
    rc, _, err = cli(capsys, "umbmark", "--runs", text)
    assert rc == 2 and "not a whole number" in err, err


def test_plain_numbers_still_read_as_before(capsys):
    """-0.5, .2, 2e-1 and +1 are plain decimals: ik gives the closed-form wheel speeds of the
    seed robot (omega_i = (-sin a_i vx + cos a_i vy + L omega) / r)."""
    rc, out, err = cli(capsys, "ik", "tomasi-omni3", "+1", "-0.5", ".2", "--json")
    assert rc == 0, err
    speeds = json.loads(out)["wheel_speeds"]
    r, L = 0.04125, 0.113
    for k in range(3):
        a = math.radians(120 * k)
        expected = (-math.sin(a) * 1 + math.cos(a) * -0.5 + L * 0.2) / r
        assert speeds[k] == pytest.approx(expected, rel=1e-9)


# --- typed text is quoted shortened, so that the reason survives -------------------------------------------
HUGE = "x" * 100_000


@pytest.mark.parametrize(
    "argv, reason",
    [
        ([HUGE], "unknown command"),
        (["ik", "tomasi-omni3", "0", "0", "0", HUGE], "unexpected argument"),
        (["ik", "tomasi-omni3", "0", "0", "0", "--" + HUGE], "unknown option"),
        (["ik", "tomasi-omni3", "0", "0", "0", "--json=" + HUGE], "ignored explicit argument"),
        (["ik", "tomasi-omni3", "0", "0", "0", "--heading", HUGE], "not a number"),
        (["odometry", "tomasi-omni3", "log.csv", "-o", "-", "--method", HUGE], "invalid choice"),
        (["odometry", "tomasi-omni3", "log.csv", "-o", "-", "--max-wheel-speed", "0" * 100_000], "chars): must be"),
        (["odometry", "tomasi-omni3", "log.csv", "-o", "-", "--max-wheel-accel", "1" * 400], "not a finite"),
        (["odometry", "tomasi-omni3", "log.csv", "-o", "-", "--counter-bits", "1" * 5000], "at most 20"),
        (["simulate", "tomasi-omni3", "--log", "-", "--path", "line 1;;" + HUGE], "empty part"),
    ],
    ids=lambda v: v if isinstance(v, str) else " ".join(a[:12] for a in v),
)
def test_a_huge_typed_value_is_quoted_short_and_the_reason_survives(capsys, argv, reason):
    """With a 100,000-character value the error line (cut at MESSAGE_LIMIT) held the value only;
    argparse said 'invalid whole value' of 5000 digits. Every path quotes the text shortened, and
    the line still says what is wrong."""
    line = one_line(*cli(capsys, *argv), reason)
    assert len(line) <= len("omnikin: error: ") + MESSAGE_LIMIT
    assert "x" * 200 not in line and "1" * 200 not in line and "0" * 200 not in line


def test_the_last_bound_of_an_error_line_keeps_its_end(capsys):
    """A library message quoting 1000 characters of a 100,000-character robot path: the line is
    cut in the middle, not at the end, so it still says what is wrong (and the presets)."""
    line = one_line(*cli(capsys, "ik", HUGE, "0", "0", "0"), "no such robot file or preset", "omni4")
    assert len(line) <= len("omnikin: error: ") + MESSAGE_LIMIT and "chars) ..." in line


def test_whole_numbers_take_at_most_twenty_digits(capsys):
    """Twenty digits hold 2**64 - 1; the 21st is refused with its count, not with int()'s digit limit."""
    rc, out, err = cli(capsys, "simulate", "diff-drive", "--path", "line 0.1", "--log", "-", "--seed", "0" * 19 + "7")
    assert rc == 0, err
    assert "--seed 7 " in out  # the log's comment: the seed as read
    one_line(*cli(capsys, "simulate", "diff-drive", "--log", "-", "--seed", "0" * 20 + "7"), "21 digits", "at most 20")


@pytest.mark.parametrize("typed", [" -1", " 1", "-1 ", "\t-1"])
def test_a_number_with_a_blank_is_refused_whatever_its_sign(capsys, typed):
    """' -1' is refused as ' 1' is: the parser takes off no blank it did not add."""
    one_line(*cli(capsys, "ik", "tomasi-omni3", typed, "0", "0"), "argument VX", "not a number", repr(typed))
    one_line(*cli(capsys, "ik", "tomasi-omni3", "0", "0", "0", "--heading", typed), "--heading", repr(typed))


def test_every_negative_value_the_help_shows_is_a_value(capsys):
    """Each example of a negative number read as a value that 'omnikin --help' gives is taken by
    'ik' as the twist's vx (none is one that every number option refuses, such as -inf)."""
    assert main(["--help"]) == 0
    text = capsys.readouterr().out
    line = next(line for line in text.splitlines() if line.startswith("negative numbers are values"))
    examples = [w.strip("(),.") for w in line.split(":", 1)[1].split() if w.startswith(("-", "(-"))]
    assert len(examples) >= 4, line
    for example in examples:
        rc, out, err = cli(capsys, "ik", "tomasi-omni3", example, "0", "0", "--json")
        assert rc == 0, (example, err)
        assert json.loads(out)["twist"][0] == float(example) < 0


@pytest.mark.parametrize(
    "baud, why",
    [
        ("0", "got 0"),
        ("-5", "got -5"),
        ("49", "got 49"),
        ("12000001", "got 12000001"),
        ("99999999999999999999", "from 50 to 12000000"),
        ("9" * 23, "at most 20"),
    ],
)
def test_ros_refuses_a_baud_rate_no_uart_runs_at_as_a_usage_error(capsys, baud, why):
    """'omnikin ros --baud 0' passed the parser and failed later as a link error (status 1)."""
    one_line(
        *cli(capsys, "ros", "diff-drive", "--backend", "serial", "--port", "/dev/omnikin-none", "--baud", baud),
        "ros: argument --baud",
        why,
    )


@pytest.mark.parametrize(
    "argv, reason",
    [
        (["simulate", "diff-drive", "--errors", HUGE, "--log", "-"], "unknown error profile"),
        (["simulate", "diff-drive", "--noise", HUGE, "--log", "-"], "unknown noise profile"),
        (["show", "diff-drive", "--plot", "a." + "x" * 200], "unknown drawing format"),
    ],
    ids=["errors", "noise", "plot"],
)
def test_names_typed_for_profiles_and_formats_are_quoted_short(capsys, argv, reason):
    line = one_line(*cli(capsys, *argv), reason)
    assert "x" * 100 not in line


@pytest.mark.parametrize("path", ["line 0", "spin 0", "spin -0", "line 0; spin 0"])
def test_a_path_that_does_not_move_writes_no_log_odometry_would_refuse(capsys, tmp_path, path):
    """A path of zero length lasts 0 s: one sample, a tick log that omnikin odometry refuses
    (it needs two). simulate refuses it instead, and writes nothing."""
    log = tmp_path / "log.csv"
    one_line(*cli(capsys, "simulate", "tomasi-omni3", "--path", path, "--log", log), "does not move the robot")
    assert not log.exists()
