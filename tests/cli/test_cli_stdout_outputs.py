"""``-o -`` means standard output in every command: where an output is a file, ``-`` writes the
data to standard output (messages go to standard error); where it is a folder (a report, a bag),
``-`` is refused in one line. Never a file or a folder named ``-``.

The outputs are discovered from the command-line parser (every command and sub-command: the
outputs declared with ``add_output`` and every ``-o`` option), so a new command is covered as
soon as it exists; each needs a small invocation in :data:`INVOCATIONS` (the test says so when
one is missing).
"""

from __future__ import annotations

import argparse
import contextlib
import signal
import subprocess

import pytest

from omnikin.cli.common import OUTPUTS
from omnikin.cli.main import build_parser
from support import servers
from support.paths import ROOT, omnikin_env

EXAMPLES = ROOT / "examples"

INVOCATIONS: dict[str, list[str]] = {
    "show": ["tomasi-omni3"],
    "odometry": ["tomasi-omni3", str(EXAMPLES / "tick_log.csv")],
    "umbmark": ["diff-drive", "--runs", "1", "--no-calibrate"],
    "calibrate": ["tomasi-omni3", str(EXAMPLES / "calibration_runs.csv")],
    "bag odometry": ["tomasi-omni3", "{bag}"],
    "bag export": ["{bag}", "--topic", "/ground_truth", "--format", "tum"],
    "simulate": ["tomasi-omni3-lidar", "--path", "line 0.2"],  # (a robot with an IMU and a lidar: every output)
    "track": ["tomasi-omni3", "circle 0.3", "--noise", "typical"],
    "sim": ["tomasi-omni3", "--duration", "1"],
    "sweep": [str(EXAMPLES / "tolerance.yaml"), "--workers", "1"],
    "mjcf": ["tomasi-omni3"],
    "urdf": ["tomasi-omni3"],
}
"""The arguments besides the output that make a quick, valid run of each command (``{bag}``: a
bag recorded by ``omnikin simulate``)."""


def _commands(parser, path=()):
    """(command path, parser) of every command and sub-command."""
    found = [(path, parser)] if path else []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                found += _commands(sub, (*path, name))
    for name, sub in getattr(parser, "_commands", {}).items():  # CommandParser.add_command
        found += _commands(sub, (*path, name))
    return found


def _outputs():
    """(command, option, declared (file or folder, '-' allowed) or None) for every output option."""
    out = []
    for path, parser in _commands(build_parser()):
        declared = {flag: (folder, stdout) for _, flag, folder, stdout in parser.get_default(OUTPUTS) or ()}
        flags = set(declared)
        for action in parser._actions:
            if "-o" in action.option_strings:
                flags.add(action.option_strings[0])
        for flag in sorted(flags):
            out.append(pytest.param(" ".join(path), flag, declared.get(flag), id=f"{' '.join(path)} {flag}"))
    return out


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    pytest.importorskip("rosbags", reason="bags need the extra 'bags'")
    folder = tmp_path_factory.mktemp("bag")
    done = subprocess.run(
        servers.omnikin("simulate", "tomasi-omni3", "--path", "line 0.2", "--bag", "run.bag"),
        cwd=folder,
        env=omnikin_env(),
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr
    return folder / "run.bag"


def test_every_command_with_an_output_is_covered():
    commands = {p.values[0] for p in _outputs()}
    assert commands, "no output option found in the parser"
    assert commands <= set(INVOCATIONS), f"add a quick invocation for {sorted(commands - set(INVOCATIONS))}"


@pytest.mark.parametrize(("command", "flag", "declared"), _outputs())
def test_dash_is_standard_output_or_refused_in_one_line(tmp_path, request, command, flag, declared):
    args = list(INVOCATIONS[command])
    if "{bag}" in args:
        args = [str(request.getfixturevalue("bag")) if a == "{bag}" else a for a in args]
    env = omnikin_env()
    if command == "sim":
        pytest.importorskip("mujoco", reason="omnikin sim needs the extra 'physics'")
        if servers.DISPLAY_MISSING:
            pytest.skip(servers.DISPLAY_MISSING)
    argv = servers.omnikin(*command.split(), *args, flag, "-")
    with servers.virtual_display() if command == "sim" else contextlib.nullcontext() as display:
        if display:
            env["DISPLAY"] = display
        proc = servers.start(argv, tmp_path, env)
        try:
            out, err = proc.communicate(timeout=600)
        except subprocess.TimeoutExpired:
            proc.send_signal(signal.SIGTERM)
            out, err = proc.communicate(timeout=60)
            pytest.fail(f"{command} {flag} - still ran after 600 s: {err[-800:]}")
    assert not (tmp_path / "-").exists() and not (tmp_path / "-").is_symlink(), f"{command} {flag} - made '-'"
    assert "Traceback" not in err, err[-800:]
    if proc.returncode == 0:  # written to standard output
        assert out, f"{command} {flag} -: nothing on standard output; stderr: {err[-800:]}"
        assert "omnikin: error" not in err
        assert declared is None or declared[1], f"{command} {flag} - wrote to standard output, declared a folder"
    else:
        lines = err.strip().splitlines()
        assert proc.returncode == 2 and len(lines) == 1 and lines[0].startswith("omnikin: error: "), err[-800:]
        assert "'-'" in lines[0] and "standard output" in lines[0], lines[0]
        assert out == ""
        assert declared is None or not declared[1], f"{command} {flag} - refused, declared for standard output"
    leftovers = [p.name for p in tmp_path.iterdir() if p.name != "MUJOCO_LOG.TXT"]
    assert leftovers == [], f"{command} {flag} - left {leftovers}"
