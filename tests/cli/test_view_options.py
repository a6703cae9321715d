"""``omnikin view``: options that do not go together, and values out of range, are one line
each, before anything is served."""

import pytest

from support.cli import run_cli


@pytest.mark.parametrize(
    "argv, words",
    [
        (["tomasi-omni3", "--ros", "--engine", "physics"], "--engine does not apply to --ros"),
        (["tomasi-omni3", "--ros", "--timeout", "1"], "--timeout does not apply to --ros"),
        (["tomasi-omni3", "--ros", "--step", "0.001"], "--step does not apply to --ros"),
        (["tomasi-omni3", "--stamped"], "--stamped applies only to --ros"),
        (["tomasi-omni3", "--ros", "--echo"], "--echo does not apply to --ros"),
        (["--replay", "somewhere", "--echo"], "--echo does not apply to --replay"),
        (["tomasi-omni3", "--ros", "--replay", "somewhere"], "--ros and --replay are two different views"),
        (["tomasi-omni3", "--step", "0.001"], "--step applies only to --engine physics"),
        (["tomasi-omni3", "--speed", "0"], "--speed must be positive"),
        (["tomasi-omni3", "--timeout", "-1"], "--timeout must be >= 0"),
        (["tomasi-omni3", "--port", "65536"], "--port must be 0 to 65535"),
        (["tomasi-omni3", "--port", "-1"], "--port must be 0 to 65535"),
        (["tomasi-omni3", "--umbmark-side", "1e6"], "--umbmark-side (0: none): the side of the UMBmark square"),
        (["tomasi-omni3", "--umbmark-side", "-2"], "--umbmark-side (0: none): the side of the UMBmark square"),
        (["tomasi-omni3", "--duration", "0"], "--duration must be positive"),
        ([], "give ROBOT"),
        (["tomasi-omni3", "--ros", "--path", "circle 1"], "--path is followed by the simulated robot of a live page"),
        (["tomasi-omni3", "--blend", "0.2"], "--blend and --smooth shape a --path file; give --path"),
        (["tomasi-omni3", "--path", "circle 1", "--smooth"], "--blend and --smooth are for path files"),
        (["tomasi-omni3", "--path", "figure9 1"], "unknown path 'figure9 1'"),
        (["tomasi-omni3", "--path", "no-such.csv"], "no-such.csv"),
    ],
)
def test_view_refuses_in_one_line(capsys, argv, words):
    rc, out, err = (
        run_cli(capsys, "view", *argv, "--port", "0") if "--port" not in argv else run_cli(capsys, "view", *argv)
    )
    assert rc == 2 and out == ""
    assert words in err and len(err.strip().splitlines()) == 1, err
