"""The Python API: omnikin.simulate, run_umbmark, analyze_umbmark, calibrate, calibration_plan,
plot_layout. Entry points exported from ``omnikin`` without making ``import omnikin`` heavy,
defaults equal to the command line's, results that plot themselves."""

from __future__ import annotations

import dataclasses
import inspect
import json
import math
import re
import subprocess
import sys

import numpy as np
import pytest

import omnikin
from omnikin.cli.main import build_parser
from support.cli import run_cli
from support.kinematics import omni_robot
from support.paths import omnikin_env

ENTRY_POINTS = ("simulate", "run_umbmark", "analyze_umbmark", "calibrate", "calibration_plan", "plot_layout")


def python(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=omnikin_env())


def test_import_omnikin_loads_neither_scipy_nor_matplotlib():
    proc = python(
        "import sys, omnikin\n"
        "heavy = sorted({m.split('.')[0] for m in sys.modules} & {'scipy', 'matplotlib', 'omnikin.api'})\n"
        "api = [m for m in sys.modules if m.startswith(('omnikin.api', 'omnikin.evaluation'))]\n"
        "print(heavy, api)"
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[] []"


def test_entry_points_are_exported_and_documented():
    for name in ENTRY_POINTS:
        function = getattr(omnikin, name)
        assert callable(function) and name in omnikin.__all__ and name in dir(omnikin)
        assert function.__doc__ and function.__doc__.strip(), name
        assert f":func:`{name}`" in omnikin.__doc__, name
    with pytest.raises(AttributeError):
        omnikin.no_such_thing  # noqa: B018


def subparser(name: str):
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    return sub.choices[name]


def argparse_defaults(parser) -> dict:
    return {a.dest: a.default for a in parser._actions if a.dest != "help"}


def signature_defaults(function) -> dict:
    return {
        n: p.default
        for n, p in inspect.signature(function).parameters.items()
        if p.default is not inspect.Parameter.empty
    }


@pytest.mark.parametrize(
    "command, function, names",
    [
        (
            "umbmark",
            omnikin.run_umbmark,
            {
                "robot": "robot",
                "true_robot": "true_robot",
                "errors": "errors",
                "mode": "mode",
                "runs": "runs",
                "side": "side",
                "noise": "noise",
                "rate": "rate",
                "seed": "seed",
                "trials": "trials",
                "calibrate": "calibrate",
                "max_memory": "max_memory",
                "max_time": "max_time",
            },
        ),
        ("umbmark", omnikin.UMBmarkReport.write, {"figures": "figure_format", "dpi": "dpi"}),
        (
            "simulate",
            omnikin.simulate,
            {
                "path": "path",
                "true_robot": "true_robot",
                "errors": "errors",
                "noise": "noise",
                "seed": "seed",
                "rate": "rate",
                "max_memory": "max_memory",
                "max_time": "max_time",
            },
        ),
        ("calibrate", omnikin.calibration_plan, {"side": "side"}),
    ],
)
def test_defaults_equal_the_command_line(command, function, names):
    cli = argparse_defaults(subparser(command))
    api = signature_defaults(function)
    for dest, param in names.items():
        assert cli[dest] == api[param], (dest, cli[dest], api[param])
        assert type(cli[dest]) is type(api[param]), dest


def test_analyze_defaults_equal_the_command_line():
    from omnikin.cli.umbmark import analyze_parser

    cli = argparse_defaults(analyze_parser())
    api = signature_defaults(omnikin.analyze_umbmark)
    assert (cli["robot"], cli["side"]) == (api["robot"], api["side"])


def test_simulate_is_omnikin_simulate_without_the_bag(tmp_path):
    pytest.importorskip("rosbags.rosbag2")

    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "omnikin.cli.main",
            "simulate",
            "tomasi-omni3",
            "--path",
            "line 1",
            "--seed",
            "5",
            "--bag",
            str(tmp_path / "s.bag"),
            "--json",
        ],
        capture_output=True,
        text=True,
        timeout=120,
        env=omnikin_env(),
    )
    assert proc.returncode == 0, proc.stderr
    cli = json.loads(proc.stdout)
    sim = omnikin.simulate("tomasi-omni3", "line 1", seed=5)
    assert sim.run.truth[0, -1].tolist() == cli["truth_end"]
    assert sim.run.odometry[-1].tolist() == cli["odometry_end"]
    assert sim.end_error.tolist() == pytest.approx(cli["end_error"], abs=1e-15)


def test_simulate_refuses_a_run_beyond_its_memory_before_starting(capsys, monkeypatch):
    """omnikin.simulate('tomasi-omni3', 'line 1400', rate=10000) is a 26 GB job: 1400 m at
    tomasi's default 0.3 m/s take 4667 s, 4.67e7 samples at 10 kHz, at least 2.2e10 bytes at the
    smallest measured 472 bytes per sample. Python and the command line refuse it alike, at once,
    each naming the limit its own way."""
    import omnikin.simulation.kinematic as kinematic
    from omnikin.errors import ResourceLimitError

    ran: list = []  # "at once": before the run, whatever the pace of the machine
    monkeypatch.setattr(
        kinematic, "simulate_kinematic", lambda *a, **k: ran.append(a) or pytest.fail("the run started")
    )
    with pytest.raises(ResourceLimitError) as info:
        omnikin.simulate("tomasi-omni3", "line 1400", rate=10000.0)
    assert ran == []
    assert info.value.unit == "bytes" and info.value.needed > 1400 / 0.3 * 1e4 * 472
    assert info.value.limit == 2 * 1024**3 and "max_memory 2G" in str(info.value) and "\n" not in str(info.value)
    rc, out, err = run_cli(capsys, "simulate", "tomasi-omni3", "--path", "line 1400", "--rate", "1e4", "--log", "-")
    assert rc == 2 and out == "" and "--max-memory 2G" in err
    pattern = r"about (\S+) of memory for (\S+) samples"
    assert re.search(pattern, err).groups() == re.search(pattern, str(info.value)).groups()
    with pytest.raises(ResourceLimitError, match=r"more than max_time 1 s; lower rate or shorten path"):
        omnikin.simulate("tomasi-omni3", "line 100", rate=10000.0, max_memory=math.inf, max_time=1.0)
    with pytest.raises(omnikin.InputError, match=r"^max_memory must be a number of bytes"):
        omnikin.simulate("tomasi-omni3", "line 1", max_memory="2G")


@pytest.mark.parametrize("wheels", [3, 12])
def test_the_memory_estimate_of_a_simulation_bounds_what_it_takes(wheels):
    """The estimate the check compares with the limit is at least the peak tracemalloc measures."""
    import tracemalloc

    from omnikin.motion.plans import parse_plan
    from omnikin.simulation.kinematic import run_cost

    robot = omni_robot([360 * k / wheels for k in range(wheels)], name=f"omni{wheels}")
    robot = omnikin.Robot(
        robot.name, tuple(dataclasses.replace(w, encoder=omnikin.Encoder(2000)) for w in robot.wheels)
    )
    omnikin.simulate(robot, "line 0.1", rate=100.0, errors="none")  # imports and caches outside the measure
    tracemalloc.start()
    try:
        sim = omnikin.simulate(robot, "line 20", rate=1000.0, errors="none")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    cost = run_cost(parse_plan("line 20"), robot, 1000.0)
    assert cost.samples + 1 >= len(sim.run.t) > 60_000  # intervals, within one sample per segment
    assert peak <= cost.bytes < 2 * peak


def test_results_plot_themselves(tmp_path):
    pytest.importorskip("matplotlib")
    from matplotlib.figure import Figure

    from omnikin.motion.plans import CalibrationRun, line, spin

    robot = omnikin.load_robot("diff-drive")
    report = omnikin.run_umbmark(robot, runs=3, rate=20.0)
    for kind in ("return_errors", "euclidean_errors", "trajectories"):
        assert isinstance(report.plot(kind), Figure)
    assert isinstance(omnikin.simulate(robot, "spin 90").plot(), Figure)
    res = omnikin.analyze_umbmark({"cw": [(0.01, 0.02), (0.02, 0.01), (0.0, 0.0)], "ccw": [(0.0, -0.01)] * 3})
    assert isinstance(res.plot(), Figure)
    assert res.e_max_syst == pytest.approx(math.hypot(0.01, 0.01), rel=1e-12)
    runs = [
        CalibrationRun(line(4.0), (4.01, 0.02, 0.0), "line 4"),
        CalibrationRun(spin(math.pi), (0, 0, 3.1), "spin 180"),
    ]
    fit = omnikin.calibrate(robot, runs)
    fig = fit.plot()
    assert isinstance(fig, Figure)
    # the residual of the nominal model is measured minus the exact path's end
    np.testing.assert_allclose(fit.residuals()["nominal"], [[0.01, 0.02], [0.0, 0.0]], atol=1e-9)
    assert isinstance(omnikin.plot_layout("mecanum4"), Figure)


def test_plotting_without_matplotlib_names_the_viz_extra():
    proc = python(
        "import sys; sys.modules['matplotlib'] = None\n"
        "import omnikin\n"
        "res = omnikin.analyze_umbmark({'cw': [(0.01, 0.0)], 'ccw': [(0.0, 0.01)]})\n"
        "print(res.e_max_syst)\n"
        "try:\n    res.plot()\nexcept ImportError as e:\n    print('ImportError:', e)"
    )
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert float(lines[0]) == pytest.approx(0.01)
    assert lines[1].startswith("ImportError:") and "omnikin[viz]" in lines[1]


def test_run_umbmark_result_is_what_the_command_writes(tmp_path):
    report = omnikin.run_umbmark("tomasi-omni3", runs=3, rate=20.0, seed=4)
    doc = report.write(tmp_path / "r")
    assert json.loads((tmp_path / "r" / "result.json").read_text(encoding="utf-8")) == doc
    assert doc == json.loads(json.dumps(report.as_dict(doc["files"])))
    from omnikin.cli.main import main

    assert main(["umbmark", "--runs", "3", "--rate", "20", "--seed", "4", "-o", str(tmp_path / "c")]) == 0
    cli = json.loads((tmp_path / "c" / "result.json").read_text(encoding="utf-8"))
    assert cli == doc


@pytest.mark.parametrize(
    "kwargs, contains",
    [
        ({"trials": 0}, "trials"),
        ({"runs": 2.5}, "runs"),
        ({"side": -1.0}, "side"),
        ({"rate": math.nan}, "rate"),
        ({"seed": -3}, "seed"),
        ({"noise": "loud"}, "loud"),
        ({"trials": 10**9}, "max_memory"),
        ({"trials": 3000, "max_time": 10.0}, "max_time"),
    ],
)
def test_run_umbmark_refuses_bad_arguments_with_one_line(kwargs, contains):
    with pytest.raises(omnikin.InputError) as info:
        omnikin.run_umbmark("diff-drive", **kwargs)
    assert contains in str(info.value) and "\n" not in str(info.value)


def test_calibration_plan_lists_what_the_robot_can_drive():
    assert omnikin.calibration_plan("diff-drive", 3.0) == [
        "square cw rotate 3",
        "square ccw rotate 3",
        "line 3 0",
        "spin 180",
        "spin -180",
        "spin 1800",
        "spin -1800",
    ]


@pytest.mark.parametrize(
    "kwargs, contains",
    [
        ({"rate": 1e-9}, "rate (--rate): the sample rate must lie in [5, 10000] Hz, got 1e-09"),
        ({"rate": 4.99}, "must lie in [5, 10000] Hz"),
        ({"rate": 1e6}, "must lie in [5, 10000] Hz"),
        ({"rate": 100 + 0j}, "rate (--rate): the sample rate must be a number"),
        ({"side": 1e-300}, "side (--side): the side of the UMBmark square must lie in [0.05, 100] m, got 1e-300"),
        ({"side": 0.049}, "must lie in [0.05, 100] m"),
        ({"side": 101.0}, "must lie in [0.05, 100] m"),
        ({"side": math.inf}, "side (--side): the side of the UMBmark square must be finite"),
        ({"side": "4"}, "must be a number, got '4'"),
    ],
)
def test_umbmark_rate_and_side_have_meaningful_bounds(kwargs, contains):
    """The bounds live in the core (evaluation.procedure): the API, its cost estimate and the
    procedure itself refuse the same settings with the same line."""
    from omnikin.api.umbmark import umbmark_cost
    from omnikin.evaluation.procedure import check_settings

    settings = {"runs": 1, "trials": 1, "side": 4.0, "rate": 100.0, **kwargs}
    for call in (
        lambda: omnikin.run_umbmark("diff-drive", calibrate=False, runs=1, **kwargs),
        lambda: umbmark_cost("diff-drive", **kwargs),
        lambda: check_settings(**settings),
    ):
        with pytest.raises(omnikin.InputError) as info:
            call()
        assert contains in str(info.value) and "\n" not in str(info.value)


def test_umbmark_runs_at_the_ends_of_its_bounds():
    small = omnikin.run_umbmark("diff-drive", side=0.05, rate=5.0, runs=1, calibrate=False, noise="none")
    assert small.side == 0.05 and small.rate == 5.0
    assert len(small.trajectories["before"]["cw"].t) > 8  # each leg and turn spans samples


def test_analyze_umbmark_side_has_the_same_bounds():
    eps = {"cw": [[0.01, 0.0]], "ccw": [[0.01, 0.0]]}
    with pytest.raises(omnikin.InputError, match=r"side \(--side\): the side of the UMBmark square must lie in"):
        omnikin.analyze_umbmark(eps, side=1e-300)
    assert omnikin.analyze_umbmark(eps, side=0.05).side == 0.05
