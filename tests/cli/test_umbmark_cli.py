"""``omnikin umbmark``, ``omnikin umbmark analyze`` and ``omnikin calibrate`` as a user runs them.

The main job runs once in a subprocess (module fixture); the other commands run in-process
through ``omnikin.cli.main.main``. Measurement files are written by hand; the expected
UMBmark and Borenstein figures were worked out with 30-digit arithmetic from eq. 1-6 of the
seed paper and the formulas of docs/conventions.md (values in the tests).
"""

from __future__ import annotations

import csv
import json
import math
import subprocess
import sys

import numpy as np
import pytest

from omnikin import load_robot
from omnikin.cli.main import main
from support.paths import ROOT, omnikin_env

PNG = b"\x89PNG\r\n\x1a\n"
SIDE_DEFAULT = 4.0


# --- helpers ----------------------------------------------------------------------------------------
def run(capsys, *argv):
    rc = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return rc, out, err


def run_json(capsys, *argv):
    rc, out, err = run(capsys, *argv)
    assert rc == 0, err
    return json.loads(out)


def assert_usage_error(capsys, *argv, contains=()):
    rc, out, err = run(capsys, *argv)
    assert rc == 2, (rc, out, err)
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("omnikin: error: "), err
    for text in contains:
        assert text in lines[0], (text, lines[0])
    return lines[0]


def r_cg_by_hand(runs):
    """Eq. 3-6: centre of gravity of the run epsilons and its distance from the origin."""
    x = sum(r["epsilon"][0] for r in runs) / len(runs)
    y = sum(r["epsilon"][1] for r in runs) / len(runs)
    return x, y, math.sqrt(x * x + y * y)


def check_direction_dict(d, n_runs):
    assert len(d["runs"]) == n_runs
    for r in d["runs"]:
        assert len(r["epsilon"]) == 3
        assert all(isinstance(v, float) and math.isfinite(v) for v in r["epsilon"])
    x, y, r = r_cg_by_hand(d["runs"])
    assert d["cg"] == pytest.approx([x, y], rel=1e-12, abs=1e-15)
    assert d["r_cg"] == pytest.approx(r, rel=1e-12)
    return r


# =====================================================================================================
# the main job (subprocess)
# =====================================================================================================
@pytest.fixture(scope="module")
def main_job(tmp_path_factory):
    cwd = tmp_path_factory.mktemp("mainjob")
    proc = subprocess.run(
        [sys.executable, "-m", "omnikin.cli.main", "umbmark"],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=120,
        env=omnikin_env(),
    )
    return cwd, proc


def test_main_job_runs_and_prints_a_table(main_job):
    cwd, proc = main_job
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    out = proc.stdout
    assert "r_cg cw [mm]" in out and "r_cg ccw [mm]" in out and "E_max,syst [mm]" in out
    assert "before" in out and "after calibration" in out
    assert "tomasi-omni3" in out


def test_main_job_report_folder(main_job):
    cwd, proc = main_job
    report = cwd / "umbmark-report"
    for name in (
        "report.md",
        "result.json",
        "return_errors.png",
        "euclidean_errors.png",
        "trajectories.png",
        "true_robot.yaml",
        "calibrated_robot.yaml",
    ):
        assert (report / name).is_file(), name
    for name in ("return_errors.png", "euclidean_errors.png", "trajectories.png"):
        assert (report / name).read_bytes()[:8] == PNG
        assert (report / name).stat().st_size > 5000
    md = (report / "report.md").read_text(encoding="utf-8")
    assert md.startswith("# UMBmark report: tomasi-omni3")
    for name in ("return_errors.png", "euclidean_errors.png", "trajectories.png"):
        assert name in md


def test_main_job_result_json(main_job):
    cwd, _ = main_job
    res = json.loads((cwd / "umbmark-report" / "result.json").read_text(encoding="utf-8"))
    for key in ("before", "after", "calibrated_robot", "units", "methods", "noise_floor"):
        assert key in res
    e = {}
    for stage in ("before", "after"):
        d = res[stage]
        r_cw = check_direction_dict(d["cw"], 5)
        r_ccw = check_direction_dict(d["ccw"], 5)
        # E_max,syst = max(r_cg_cw, r_cg_ccw)
        assert d["e_max_syst"] == pytest.approx(max(r_cw, r_ccw), rel=1e-12)
        low, high = d["e_max_syst_interval"]
        assert low <= d["e_max_syst"] <= high
        # at the noise floor exactly when at or below the floor's 95th percentile
        assert d["at_noise_floor"] == (d["e_max_syst"] <= res["noise_floor"]["e_max_syst_p95"])
        e[stage] = d["e_max_syst"]
    assert res["reduction_factor"] >= 20
    assert res["reduction_factor"] == pytest.approx(e["before"] / e["after"], rel=1e-12)
    low, high = res["reduction_factor_interval"]
    assert low <= res["reduction_factor"] and (high is None or res["reduction_factor"] <= high)
    assert res["settings"]["robot"] == "tomasi-omni3" and res["settings"]["calibrate"] is True
    assert res["settings"]["errors"] == "typical" and res["settings"]["noise"] == "typical"
    for key in ("e_max_syst", "r_cg", "cg", "side", "rate", "e_max_syst_p95", "reduction_factor"):
        assert key in res["units"], key
    assert res["units"]["e_max_syst"] == "m" and res["units"]["rate"] == "Hz"


def test_main_job_report_says_when_after_is_at_the_noise_floor(main_job):
    cwd, _ = main_job
    report = cwd / "umbmark-report"
    res = json.loads((report / "result.json").read_text(encoding="utf-8"))
    md = (report / "report.md").read_text(encoding="utf-8")
    assert ("After calibration, E_max,syst" in md) == res["after"]["at_noise_floor"]
    assert "Hotelling" in md and "95th percentile" in md


def test_main_job_robot_files(main_job):
    cwd, _ = main_job
    report = cwd / "umbmark-report"
    res = json.loads((report / "result.json").read_text(encoding="utf-8"))
    nominal = load_robot("tomasi-omni3")
    true = load_robot(report / "true_robot.yaml")
    calibrated = load_robot(report / "calibrated_robot.yaml")
    assert calibrated.wheel_names == nominal.wheel_names == true.wheel_names
    # the true robot is the nominal one with the injected radius errors
    for name, e in res["injected_errors"].items():
        assert true.wheel(name).radius == pytest.approx(nominal.wheel(name).radius * (1 + e["radius"]), rel=1e-6)
    # the calibrated kinematics differ from the nominal and are closer to the truth
    j_nom, j_true, j_cal = nominal.ik_matrix, true.ik_matrix, calibrated.ik_matrix
    assert np.max(np.abs(j_cal - j_nom)) > 1e-3 * np.max(np.abs(j_nom))
    assert np.linalg.norm(j_cal - j_true) < np.linalg.norm(j_nom - j_true)


def test_main_job_measurements_feed_analyze(main_job, capsys):
    """The report's measurements file is the input format of 'umbmark analyze': same E_max,syst."""
    cwd, _ = main_job
    report = cwd / "umbmark-report"
    res = json.loads((report / "result.json").read_text(encoding="utf-8"))
    d = run_json(capsys, "umbmark", "analyze", report / "measurements_before.csv", "--json")
    assert d["e_max_syst"] == pytest.approx(res["before"]["e_max_syst"], abs=2e-6)


def test_calibrate_from_report_runs(main_job, capsys, tmp_path):
    cwd, _ = main_job
    report = cwd / "umbmark-report"
    res = json.loads((report / "result.json").read_text(encoding="utf-8"))
    out = tmp_path / "out.yaml"
    d = run_json(capsys, "calibrate", "tomasi-omni3", report / "calibration_runs.csv", "-o", out, "--json")
    assert out.is_file()
    calibrated = load_robot(out)
    nominal = load_robot("tomasi-omni3")
    assert calibrated.wheel_names == nominal.wheel_names
    assert np.max(np.abs(calibrated.ik_matrix - nominal.ik_matrix)) > 1e-3 * np.max(np.abs(nominal.ik_matrix))
    # the same runs (written to 1 um / 1e-5 deg), weighted the same way, give the main job's estimates
    main = {p["name"]: p for p in res["calibration"]["parameters"]}
    assert [p["name"] for p in d["parameters"]] == list(main)
    for p in d["parameters"]:
        assert p["unit"] == main[p["name"]]["unit"]
        assert p["value"] == pytest.approx(main[p["name"]]["value"], abs=3 * main[p["name"]]["sigma"] * 1e-2)
    # the table prints every parameter with the unit result.json gives it
    rc, text, err = run(capsys, "calibrate", "tomasi-omni3", report / "calibration_runs.csv")
    assert rc == 0, err
    rows = {line.split()[1]: line for line in text.splitlines() if line.startswith("│ w")}
    assert set(rows) == set(main)
    for name, p in main.items():
        assert p["unit"] in rows[name]


# =====================================================================================================
# omnikin umbmark with options (in-process)
# =====================================================================================================
FAST = ("--runs", "3", "--rate", "20")


def read_result(folder):
    return json.loads((folder / "result.json").read_text(encoding="utf-8"))


def test_umbmark_json_prints_result_json(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    rc, out, err = run(capsys, "umbmark", "tomasi-omni3", "--json", *FAST)
    assert rc == 0, err
    assert out == (tmp_path / "umbmark-report" / "result.json").read_text(encoding="utf-8")
    d = json.loads(out)
    assert d["after"]["e_max_syst"] == pytest.approx(
        max(check_direction_dict(d["after"]["cw"], 3), check_direction_dict(d["after"]["ccw"], 3))
    )
    assert "borenstein" not in d["before"]
    assert d["files"] and set(d["files"]) <= {p.name for p in (tmp_path / "umbmark-report").iterdir()}


def test_umbmark_json_diff_drive_borenstein(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    d = run_json(capsys, "umbmark", "diff-drive", "--json", "--out", "dd", *FAST)
    b = d["before"]["borenstein"]
    assert set(b) >= {"alpha", "beta", "R", "E_d", "E_b", "c_L", "c_R", "b_new"}
    # Borenstein's figures from the printed centres of gravity (L = 4 m, b = 0.33 m)
    x_cw, x_ccw = d["before"]["cw"]["cg"][0], d["before"]["ccw"]["cg"][0]
    assert b["alpha"] == pytest.approx((x_cw + x_ccw) / -16.0, rel=1e-12)
    assert b["beta"] == pytest.approx((x_cw - x_ccw) / -16.0, rel=1e-12)
    assert b["c_R"] / b["c_L"] == pytest.approx(b["E_d"], rel=1e-12)
    assert b["b_new"] == pytest.approx(0.33 * b["E_b"], rel=1e-12)
    assert len(d["borenstein_iterations"]) == 3
    assert (tmp_path / "dd" / "report.md").is_file()
    d = run_json(capsys, "umbmark", "diff-drive", "--json", "-o", "dd2", "--no-calibrate", *FAST)
    assert "calibration" not in d and "after" not in d and "borenstein" in d["before"]


def test_umbmark_without_robot_is_the_same_study_as_naming_the_default_robot(capsys, tmp_path, monkeypatch):
    """No hidden special case for the default run: 'omnikin umbmark' = 'omnikin umbmark tomasi-omni3'."""
    monkeypatch.chdir(tmp_path)
    a = run_json(capsys, "umbmark", "--json", "-o", "a", *FAST)
    b = run_json(capsys, "umbmark", "tomasi-omni3", "--json", "-o", "b", *FAST)
    assert a == b
    assert "calibration" in a  # calibration is the default for every robot
    c = run_json(capsys, "umbmark", "diff-drive", "--json", "-o", "c", *FAST)
    assert "calibration" in c


def test_same_seed_builds_the_same_robot_and_calibration_whatever_the_trials(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    one = run_json(capsys, "umbmark", "--json", "-o", "one", "--seed", "5", *FAST)
    many = run_json(capsys, "umbmark", "--json", "-o", "many", "--seed", "5", "--trials", "3", *FAST)
    other = run_json(capsys, "umbmark", "--json", "-o", "other", "--seed", "6", *FAST)
    assert one["true_robot"] == many["true_robot"] and one["injected_errors"] == many["injected_errors"]
    assert one["calibrated_robot"] == many["calibrated_robot"]

    def data(folder):
        text = (tmp_path / folder / "calibration_runs.csv").read_text(encoding="utf-8")
        return [line for line in text.splitlines() if not line.startswith("#")]

    assert data("one") == data("many")
    assert one["true_robot"] != other["true_robot"]
    # the robot drawn for a seed is the one 'omnikin simulate --seed' and omnikin.simulate draw
    import omnikin

    sim = omnikin.simulate("tomasi-omni3", "line 1", seed=5)
    assert sim.injected.as_dict() == one["injected_errors"]


def test_umbmark_calibration_runs_file_keeps_side(capsys, tmp_path, monkeypatch):
    from omnikin.io.runs import read_calibration_runs

    monkeypatch.chdir(tmp_path)
    run_json(capsys, "umbmark", "--side", "2", "--json", *FAST)
    runs = read_calibration_runs(tmp_path / "umbmark-report" / "calibration_runs.csv")
    squares = [r for r in runs if r.label.startswith("square")]
    assert squares
    for r in squares:
        legs = [s.length for s in r.plan.segments if s.xi[2] == 0.0]
        assert legs == pytest.approx([2.0] * 4), r.label
    lines = [r for r in runs if r.label.startswith("line")]
    assert all(r.plan.segments[0].length == pytest.approx(2.0) for r in lines)


def test_umbmark_report_names_the_number_of_runs(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    run_json(capsys, "umbmark", "tomasi-omni3", "--json", *FAST)
    md = (tmp_path / "umbmark-report" / "report.md").read_text(encoding="utf-8")
    assert "3 runs per direction" in md
    assert "of 5 runs" not in md


def test_a_perfect_robot_without_noise_is_reported_at_the_noise_floor(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    from omnikin.io.robot_file import save_robot

    save_robot(load_robot("diff-drive"), tmp_path / "perfect.yaml")
    d = run_json(
        capsys,
        "umbmark",
        "diff-drive",
        "--true-robot",
        "perfect.yaml",
        "--noise",
        "none",
        "--json",
        "--no-calibrate",
        *FAST,
    )
    assert d["before"]["e_max_syst"] < 1e-9
    assert d["before"]["at_noise_floor"] is True
    assert "Before calibration, E_max,syst" in (tmp_path / "umbmark-report" / "report.md").read_text(encoding="utf-8")


# --- the report folder: omnikin.io.output ------------------------------------------------------------------
def folder_files(folder):
    return sorted(p.name for p in folder.iterdir())


def test_the_same_command_twice_replaces_the_report_as_a_whole(capsys, tmp_path, monkeypatch):
    from omnikin.io.output import REPORT_MARKER

    monkeypatch.chdir(tmp_path)
    first = run_json(capsys, "umbmark", "--json", "--trials", "2", *FAST)
    assert "monte_carlo.png" in first["files"] and "calibrated_robot.yaml" in first["files"]
    second = run_json(capsys, "umbmark", "--json", "--no-calibrate", *FAST)
    # nothing of the first run is left: exactly the second run's files
    assert folder_files(tmp_path / "umbmark-report") == sorted(second["files"] + [REPORT_MARKER])
    assert "monte_carlo.png" not in second["files"] and "calibrated_robot.yaml" not in second["files"]
    third = run_json(capsys, "umbmark", "--json", "--no-calibrate", *FAST)
    assert third == second
    assert sorted(p.name for p in tmp_path.iterdir()) == ["umbmark-report"]  # no staging left behind


def test_a_foreign_folder_is_refused_and_left_alone(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    mine = tmp_path / "thesis"
    mine.mkdir()
    (mine / "chapter1.tex").write_text("precious", encoding="utf-8")
    line = assert_usage_error(capsys, "umbmark", "-o", "thesis", *FAST, contains=["thesis"])
    assert "did not write" in line
    assert folder_files(mine) == ["chapter1.tex"]
    assert (mine / "chapter1.tex").read_text(encoding="utf-8") == "precious"
    # an empty folder is fine
    (tmp_path / "empty").mkdir()
    run_json(capsys, "umbmark", "-o", "empty", "--json", "--no-calibrate", *FAST)


def test_the_report_folder_is_never_an_input(capsys, tmp_path, monkeypatch):
    from omnikin.io.robot_file import save_robot

    monkeypatch.chdir(tmp_path)
    save_robot(load_robot("diff-drive"), tmp_path / "robot.yaml")
    assert_usage_error(capsys, "umbmark", "robot.yaml", "-o", "robot.yaml", *FAST, contains=["robot.yaml"])
    assert load_robot(tmp_path / "robot.yaml").name == "diff-drive"
    assert_usage_error(capsys, "umbmark", "-o", "-", *FAST, contains=["folder"])


def test_an_interrupted_run_leaves_the_previous_report_intact(tmp_path):
    """Ctrl-C while the report is being written: the old report stays, nothing half written."""
    import signal
    import time

    env = omnikin_env()
    base = [sys.executable, "-m", "omnikin.cli.main", "umbmark", "--runs", "3", "--rate", "20"]
    done = subprocess.run(base, cwd=tmp_path, env=env, capture_output=True, timeout=120)
    assert done.returncode == 0, done.stderr
    report = tmp_path / "umbmark-report"
    before = {p.name: p.read_bytes() for p in report.iterdir()}
    # a slow write (large PNGs), interrupted as soon as its staging folder appears
    proc = subprocess.Popen(
        base + ["--seed", "2", "--dpi", "900"],
        cwd=tmp_path,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    deadline = time.monotonic() + 120
    staged = False
    while proc.poll() is None and time.monotonic() < deadline:
        if any(p.name.startswith(".umbmark-report.") for p in tmp_path.iterdir()):
            proc.send_signal(signal.SIGINT)
            staged = True
            break
        time.sleep(0.005)
    proc.wait(timeout=60)
    assert staged, "the run finished before it could be interrupted"
    assert proc.returncode != 0
    assert {p.name: p.read_bytes() for p in report.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["umbmark-report"]


@pytest.mark.parametrize(
    "argv, contains",
    [
        (["--trials", "3000", "--max-time", "10"], ["umbmark", "--max-time 10 s", "--trials"]),
        (["--trials", "20000000", "--runs", "1", "--rate", "5"], ["umbmark", "--max-memory 2G", "--trials"]),
    ],
)
def test_umbmark_refuses_studies_beyond_the_budget_at_once(capsys, tmp_path, monkeypatch, argv, contains):
    monkeypatch.chdir(tmp_path)
    _study_must_not_run(monkeypatch)
    assert_usage_error(capsys, "umbmark", *argv, contains=contains)
    assert not (tmp_path / "umbmark-report").exists()


def _study_must_not_run(monkeypatch) -> None:
    """Refused "at once" means before the study: the study itself fails the test if it starts
    (whatever the pace of the machine)."""
    import omnikin.api.umbmark as api

    def study(*args, **kwargs):
        raise AssertionError("the study ran before the refusal")

    # the trials themselves: run_umbmark checks its cost before it calls them
    monkeypatch.setattr(api, "umbmark_study", study)  # the one study of both engines


# =====================================================================================================
# omnikin umbmark analyze on hand-written measurement files
# =====================================================================================================
HAND = """direction,x_abs,y_abs,x_calc,y_calc
cw,0.10,-0.05,0.02,0.01
cw,0.12,-0.03,0.02,0.01
cw,0.09,-0.06,-0.01,0.00
ccw,0.03,0.07,0.01,-0.02
ccw,0.05,0.06,0.01,-0.02
ccw,0.02,0.08,0.01,-0.02
ccw,0.04,0.05,0.01,-0.02
"""
# eps = abs - calc: cw (0.08, -0.06), (0.10, -0.04), (0.10, -0.06); ccw (0.02, 0.09), (0.04, 0.08),
# (0.01, 0.10), (0.03, 0.07). cg_cw = (0.28/3, -0.16/3), r = sqrt(0.104)/3; cg_ccw = (0.025, 0.085),
# r = sqrt(0.00785).
HAND_CG = {"cw": (0.28 / 3, -0.16 / 3), "ccw": (0.025, 0.085)}
HAND_R = {"cw": 0.107496769977313995364888176404, "ccw": 0.0886002257333467520099556254877}
HAND_BORENSTEIN = {
    4.0: dict(
        alpha=-0.00739583333333333333333,
        beta=-0.00427083333333333333333,
        R=-936.586077659592773238987,
        E_d=0.99964771857981259868773,
        E_b=0.995313730786286244601320,
        c_L=1.00017617174110927808797,
        c_R=0.999823828258890721912028,
        b_new=0.32845353115947446071843577,
    ),
    2.0: dict(
        alpha=-0.0147916666666666666666667,
        beta=-0.00854166666666666666666,
        R=-234.147053270484916279079,
        E_d=0.998591621748032505496304,
        E_b=0.990671178939508514956046,
        c_L=1.00070468535774991470854,
        c_R=0.999295314642250085291460,
        b_new=0.326921489050037809935495,
    ),
}


@pytest.mark.parametrize("side", [4.0, 2.0])
def test_analyze_hand_file(capsys, tmp_path, side):
    f = tmp_path / "measured.csv"
    f.write_text(HAND, encoding="utf-8")
    argv = ["umbmark", "analyze", f, "--robot", "diff-drive", "--json"] + ([] if side == 4.0 else ["--side", "2"])
    d = run_json(capsys, *argv)
    eps = {
        "cw": [(0.08, -0.06), (0.10, -0.04), (0.10, -0.06)],
        "ccw": [(0.02, 0.09), (0.04, 0.08), (0.01, 0.10), (0.03, 0.07)],
    }
    for direction in ("cw", "ccw"):
        runs = d[direction]["runs"]
        assert len(runs) == len(eps[direction])
        for r, (x, y) in zip(runs, eps[direction], strict=True):
            assert r["epsilon"][:2] == pytest.approx([x, y], abs=1e-15)
            assert r["epsilon"][2] is None  # heading not measured
        assert d[direction]["cg"] == pytest.approx(HAND_CG[direction], abs=1e-15)
        assert d[direction]["r_cg"] == pytest.approx(HAND_R[direction], rel=1e-13)
    assert d["e_max_syst"] == pytest.approx(HAND_R["cw"], rel=1e-13)
    assert d["side"] == side
    for key, value in HAND_BORENSTEIN[side].items():
        assert d["borenstein"][key] == pytest.approx(value, rel=1e-12), key


def test_analyze_table_output_and_non_diff_robot(capsys, tmp_path):
    f = tmp_path / "measured.csv"
    f.write_text(HAND, encoding="utf-8")
    rc, out, err = run(capsys, "umbmark", "analyze", f, "--robot", "diff-drive")
    assert rc == 0, err
    assert "107.50" in out and "88.60" in out  # r_cg in mm
    assert "Borenstein" in out
    d = run_json(capsys, "umbmark", "analyze", f, "--robot", "tomasi-omni3", "--json")
    assert "borenstein" not in d and d["e_max_syst"] == pytest.approx(HAND_R["cw"], rel=1e-13)
    d = run_json(capsys, "umbmark", "analyze", f, "--json")
    assert "borenstein" not in d


def test_analyze_theta_columns(capsys, tmp_path):
    deg = tmp_path / "deg.csv"
    deg.write_text(
        "direction,x_abs,y_abs,x_calc,y_calc,theta_abs_deg,theta_calc_deg\n"
        "cw,0.01,0.02,0,0,10,4\n"
        "ccw,0.01,0.02,0,0,179,-179\n"
        "ccw,0.01,0.02,0,0,-3,2\n",
        encoding="utf-8",
    )
    d = run_json(capsys, "umbmark", "analyze", deg, "--json")
    assert d["cw"]["runs"][0]["epsilon"][2] == pytest.approx(math.radians(6.0), rel=1e-12)
    assert d["ccw"]["runs"][0]["epsilon"][2] == pytest.approx(math.radians(-2.0), rel=1e-9)  # wrapped
    assert d["ccw"]["runs"][1]["epsilon"][2] == pytest.approx(math.radians(-5.0), rel=1e-12)
    rad = tmp_path / "rad.csv"
    rad.write_text(
        "direction,x_abs,y_abs,x_calc,y_calc,theta_abs,theta_calc\n"
        "cw,0.01,0.02,0,0,0.1,0.02\n"
        "ccw,0.03,0.04,0,0,-0.1,0.05\n",
        encoding="utf-8",
    )
    d = run_json(capsys, "umbmark", "analyze", rad, "--json")
    assert d["cw"]["runs"][0]["epsilon"][2] == pytest.approx(0.08, rel=1e-12)
    assert d["ccw"]["runs"][0]["epsilon"][2] == pytest.approx(-0.15, rel=1e-12)
    assert d["e_max_syst"] == pytest.approx(0.05, rel=1e-12)
    # an empty theta field is an error naming line and column, not a run without heading
    rad.write_text(
        "direction,x_abs,y_abs,x_calc,y_calc,theta_abs,theta_calc\ncw,0.01,0.02,0,0,0.1,0.02\nccw,0.03,0.04,0,0,,\n",
        encoding="utf-8",
    )
    rc, _, err = run(capsys, "umbmark", "analyze", rad, "--json")
    assert rc == 2 and "line 3, column 'theta_abs'" in err and "empty field" in err
    # comments, blank lines and a BOM as spreadsheets write them
    bom = tmp_path / "bom.csv"
    bom.write_bytes(
        "\ufeff# measured 2024-05-01\ndirection,x_abs,y_abs,x_calc,y_calc\n\ncw,0.03,0.04,0,0\nCCW,0,0.01,0,0\n".encode(
            "utf-8"
        )
    )
    d = run_json(capsys, "umbmark", "analyze", bom, "--json")
    assert d["e_max_syst"] == pytest.approx(0.05, rel=1e-12)


# =====================================================================================================
# omnikin calibrate on a runs file written from simulate_kinematic()
# =====================================================================================================
def test_calibrate_own_runs_file(capsys, tmp_path):
    from omnikin.motion.plans import line, spin, umbmark_square
    from omnikin.simulation.error_models import NoiseModel, SystematicErrors, WheelErrors
    from omnikin.simulation.kinematic import simulate_kinematic

    robot = load_robot("diff-drive")
    true = SystematicErrors(
        {"left": WheelErrors(radius=-0.004, dy=0.002), "right": WheelErrors(radius=0.006, dy=-0.001)}
    ).apply(robot)
    plans = {
        "square cw rotate": umbmark_square("cw"),
        "square ccw rotate": umbmark_square("ccw"),
        "line 4": line(4.0),
        "spin 180": spin(math.pi),
        "spin -180": spin(-math.pi),
    }
    path = tmp_path / "runs.csv"
    with open(path, "w", newline="", encoding="utf-8") as handle:
        w = csv.writer(handle)
        w.writerow(["path", "x_abs", "y_abs", "theta_abs_deg"])
        for text, plan in plans.items():
            m = simulate_kinematic(plan, true, robot, noise=NoiseModel(quantise=False), rate=50.0).measured[0]
            w.writerow([text, f"{m[0]:.7f}", f"{m[1]:.7f}", f"{math.degrees(m[2]):.6f}"])
    out = tmp_path / "calibrated.json"
    rc, text, err = run(capsys, "calibrate", "diff-drive", path, "-o", out)
    assert rc == 0, err
    assert "calibrated robot written to" in text
    cal = load_robot(out)
    for name, e in (("left", -0.004), ("right", 0.006)):
        assert cal.wheel(name).radius == pytest.approx(0.0825 * (1 + e), rel=1e-4)
    assert cal.wheel("left").y - cal.wheel("right").y == pytest.approx(0.33 + 0.003, abs=1e-5)
    assert np.max(np.abs(cal.ik_matrix - robot.ik_matrix)) > 1e-4


# =====================================================================================================
# bad input: exit 2, one line, no traceback
# =====================================================================================================
@pytest.mark.parametrize(
    "content, contains",
    [
        ("direction,x_abs,y_abs,x_calc\ncw,1,2,3\n", ["y_calc"]),  # missing column
        ("direction,x_abs,y_abs,x_calc,y_calc\ncw,1,nan,0,0\nccw,1,2,0,0\n", ["line 2", "y_abs"]),  # NaN
        ("direction,x_abs,y_abs,x_calc,y_calc\ncw,1,2,0,0\ncw,1,2,0,0\n", ["ccw"]),  # one direction
        ("direction,x_abs,y_abs,x_calc,y_calc\n", []),  # no runs
        ("", ["empty"]),  # empty file
        ("direction,x_abs,y_abs,x_calc,y_calc\ncw,1,2,0,0\nccw,,2,0,0\n", ["line 3", "x_abs"]),
        ("direction,x_abs,y_abs,x_calc,y_calc\ncw,1,2,0,0\nup,1,2,0,0\n", ["line 3", "direction"]),
        ("direction,x_abs,y_abs,x_calc,y_calc\ncw,1,2,0,0\nccw,1,2,0\n", ["line 3"]),
    ],
)
def test_analyze_bad_files(capsys, tmp_path, content, contains):
    f = tmp_path / "bad.csv"
    f.write_text(content, encoding="utf-8")
    assert_usage_error(capsys, "umbmark", "analyze", f, "--robot", "diff-drive", contains=[str(f), *contains])


def test_analyze_missing_file_and_bad_side(capsys, tmp_path):
    assert_usage_error(capsys, "umbmark", "analyze", tmp_path / "nope.csv", contains=["nope.csv"])
    f = tmp_path / "measured.csv"
    f.write_text(HAND, encoding="utf-8")
    assert_usage_error(capsys, "umbmark", "analyze", f, "--side", "-2", contains=["side"])


@pytest.mark.parametrize(
    "argv, contains",
    [
        (["--runs", "0"], ["--runs"]),
        (["--runs", "-3"], ["--runs"]),
        (["--trials", "0"], ["--trials"]),
        (["--side", "-1"], ["--side"]),
        (["--side", "0"], ["--side"]),
        (["--side", "nan"], ["--side"]),
        (["--errors", "bogus"], ["bogus"]),
        (["--noise", "bogus"], ["bogus"]),
        (["diff-drive", "--mode", "translate"], ["'translate' mode", "'left'", "the other mode is 'rotate'"]),
        (["ackermann"], ["'rotate' mode", "front_left", "nor in the other mode"]),
        (["--dpi", "0"], ["dpi"]),
        (["--dpi", "nan"], ["dpi"]),
        (["no-such-robot"], ["no-such-robot"]),
        (["--rate", "0"], ["rate"]),
    ],
)
def test_umbmark_bad_options(capsys, tmp_path, monkeypatch, argv, contains):
    monkeypatch.chdir(tmp_path)
    assert_usage_error(capsys, "umbmark", *argv, contains=contains)
    assert not (tmp_path / "umbmark-report").exists()


@pytest.mark.parametrize("dpi", ["1", "0.5", "49.99", "1201", "1e9"])
def test_umbmark_refuses_a_resolution_outside_screens_to_print_before_the_study(capsys, tmp_path, monkeypatch, dpi):
    """A resolution FreeType cannot draw ('--dpi 1') or that gives figures of a few pixels
    ('--dpi 0.5') is a usage error naming --dpi and the range (50 dpi, the coarsest screens, to
    1200 dpi, print), before any simulation."""
    _study_must_not_run(monkeypatch)
    line = assert_usage_error(
        capsys, "umbmark", "diff-drive", "--dpi", dpi, "-o", tmp_path / "r", contains=["--dpi", "[50, 1200] dpi"]
    )
    assert "internal error" not in line
    assert list(tmp_path.iterdir()) == []


def test_umbmark_negative_seed(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert_usage_error(capsys, "umbmark", "--seed", "-1", "--runs", "1", "--rate", "20", contains=["seed"])


@pytest.mark.parametrize(
    "content, contains",
    [
        ("path,x_abs,y_abs\nline 4,4.01,0\nhop 3,1,1\n", ["line 3", "'path'", "hop 3"]),  # unknown path
        ("path,x_abs,y_abs\nline 4,4.01,0\nsquare cw,1,1\n", ["line 3", "'path'"]),
        ("path,x_abs,y_abs\nline 4,4.01,0\nline four,1,1\n", ["line 3", "'path'"]),
        ("path,x_abs,y_abs\nline 4,4.01,0\narc -1 90,1,1\n", ["line 3", "'path'"]),
        ("path,x_abs,y_abs\n\n# comment\nline 4,4.01,0\nspin 90,nan,0\n", ["line 5", "x_abs"]),
        ("", ["empty"]),
        ("path,x_abs\nline 4,4.01\n", ["y_abs"]),
    ],
)
def test_calibrate_bad_runs_files(capsys, tmp_path, content, contains):
    f = tmp_path / "runs.csv"
    f.write_text(content, encoding="utf-8")
    assert_usage_error(capsys, "calibrate", "tomasi-omni3", f, "-o", tmp_path / "o.yaml", contains=contains)
    assert not (tmp_path / "o.yaml").exists()


# =====================================================================================================
# omnikin calibrate: runs it cannot drive, outputs, --plan
# =====================================================================================================
def test_calibrate_refuses_a_runs_file_with_a_path_the_robot_cannot_drive(capsys, tmp_path):
    f = tmp_path / "runs.csv"
    f.write_text("path,x_abs,y_abs\nline 4,4.0,0\n# sideways next\nline 1 90,0,1\n", encoding="utf-8")
    assert_usage_error(
        capsys,
        "calibrate",
        "diff-drive",
        f,
        "-o",
        tmp_path / "o.yaml",
        contains=[f"{f}: line 4", "'line 1 90'", "diff-drive", "left"],
    )
    assert not (tmp_path / "o.yaml").exists()


def write_runs(path, robot, true, plans):
    from omnikin.simulation.error_models import NoiseModel
    from omnikin.simulation.kinematic import simulate_kinematic

    with open(path, "w", newline="", encoding="utf-8") as handle:
        w = csv.writer(handle)
        w.writerow(["path", "x_abs", "y_abs", "theta_abs_deg"])
        for text in plans:
            from omnikin.motion.plans import parse_plan

            m = simulate_kinematic(parse_plan(text), true, robot, noise=NoiseModel(quantise=False), rate=50.0).measured[
                0
            ]
            w.writerow([text, f"{m[0]:.7f}", f"{m[1]:.7f}", f"{math.degrees(m[2]):.6f}"])


def test_calibrate_output_is_never_an_input_and_needs_force_to_replace(capsys, tmp_path):
    runs = tmp_path / "runs.csv"
    robot = load_robot("diff-drive")
    write_runs(runs, robot, robot, ["line 4 0", "spin 180", "square cw rotate 4"])
    original = runs.read_bytes()
    assert_usage_error(capsys, "calibrate", "diff-drive", runs, "-o", runs, contains=["runs.csv", "input"])
    assert_usage_error(capsys, "calibrate", "diff-drive", runs, "-o", runs, "--force", contains=["input"])
    assert runs.read_bytes() == original
    out = tmp_path / "cal.yaml"
    out.write_text("mine", encoding="utf-8")
    assert_usage_error(capsys, "calibrate", "diff-drive", runs, "-o", out, contains=["cal.yaml", "--force"])
    assert out.read_text(encoding="utf-8") == "mine"
    rc, text, err = run(capsys, "calibrate", "diff-drive", runs, "-o", out, "--force")
    assert rc == 0, err
    assert load_robot(out).wheel("left").radius == pytest.approx(0.0825, rel=1e-6)
    # the robot file given as ROBOT is an input too
    from omnikin.io.robot_file import save_robot

    save_robot(robot, tmp_path / "dd.yaml")
    assert_usage_error(
        capsys, "calibrate", tmp_path / "dd.yaml", runs, "-o", tmp_path / "dd.yaml", "--force", contains=["input"]
    )


def test_calibrate_plan_prints_the_runs_to_drive_as_a_runs_file(capsys, tmp_path):
    from omnikin.io.runs import read_calibration_runs

    rc, text, err = run(capsys, "calibrate", "diff-drive", "--plan")
    assert rc == 0, err
    lines = text.splitlines()
    header = [line for line in lines if not line.startswith("#")][0]
    assert header == "path,x_abs,y_abs,theta_abs_deg"
    rows = [line.split(",")[0] for line in lines if not line.startswith("#")][1:]
    # every recommended path five times, and nothing a differential drive cannot drive
    assert sorted(set(rows)) == sorted(
        ["square cw rotate 4", "square ccw rotate 4", "line 4 0", "spin 180", "spin -180", "spin 1800", "spin -1800"]
    )
    assert all(rows.count(p) == 5 for p in set(rows))
    # filled in with measurements, the template is a runs file omnikin calibrate reads
    robot = load_robot("diff-drive")
    from omnikin.simulation.error_models import SystematicErrors, WheelErrors

    true = SystematicErrors({"left": WheelErrors(radius=0.004), "right": WheelErrors(radius=-0.002)}).apply(robot)
    filled = tmp_path / "filled.csv"
    write_runs(filled, robot, true, rows)
    assert len(read_calibration_runs(filled)) == len(rows)
    d = run_json(capsys, "calibrate", "diff-drive", filled, "--json")
    values = {p["name"]: p["value"] for p in d["parameters"]}
    assert values["left.radius"] == pytest.approx(0.004, rel=1e-3)
    assert values["right.radius"] == pytest.approx(-0.002, rel=1e-3)
    # --plan -o writes the template by the output policy; --plan takes no RUNS
    out = tmp_path / "plan.csv"
    rc, _, err = run(capsys, "calibrate", "ackermann", "--plan", "-o", out)
    assert rc == 0, err
    paths = {r[0] for r in data_rows(out)[1:]}
    assert paths == {"line 4 0", "arc 2 180", "arc 2 -180"}  # a car cannot turn in place
    assert_usage_error(capsys, "calibrate", "ackermann", "--plan", "-o", out, contains=["--force"])
    assert_usage_error(capsys, "calibrate", "ackermann", filled, "--plan", contains=["--plan"])
    assert_usage_error(capsys, "calibrate", "ackermann", contains=["RUNS"])


# =====================================================================================================
# the sample data in examples/
# =====================================================================================================
EXAMPLES = ROOT / "examples"


def data_rows(path):
    with open(path, newline="", encoding="utf-8") as handle:
        return [r for r in csv.reader(handle) if r and not r[0].startswith("#")]


def test_examples_run_as_written_on_a_fresh_clone(tmp_path):
    import shutil

    shutil.copytree(EXAMPLES, tmp_path / "examples")
    for argv in (
        ["umbmark", "analyze", "examples/umbmark_measurements.csv", "--robot", "tomasi-omni3"],
        ["calibrate", "tomasi-omni3", "examples/calibration_runs.csv", "-o", "calibrated.yaml"],
    ):
        proc = subprocess.run(
            [sys.executable, "-m", "omnikin.cli.main", *argv],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=120,
            env=omnikin_env(),
        )
        assert proc.returncode == 0, proc.stderr
        assert proc.stderr == ""
    assert load_robot(tmp_path / "calibrated.yaml").wheel_names == load_robot("tomasi-omni3").wheel_names
    for name in ("umbmark_measurements.csv", "calibration_runs.csv"):
        first = (EXAMPLES / name).read_text(encoding="utf-8").splitlines()[0]
        assert first.startswith("# ") and "generated by omnikin" in first


def test_examples_are_what_omnikin_umbmark_writes(main_job):
    """The sample data is the main job's output (as its '#' lines say): same rows, to the printed digits."""
    cwd, _ = main_job
    report = cwd / "umbmark-report"
    for example, written in (
        ("umbmark_measurements.csv", "measurements_before.csv"),
        ("calibration_runs.csv", "calibration_runs.csv"),
    ):
        ours, theirs = data_rows(EXAMPLES / example), data_rows(report / written)
        assert ours[0] == theirs[0] and len(ours) == len(theirs)
        for a, b in zip(ours[1:], theirs[1:], strict=True):
            assert a[0] == b[0]
            assert [float(v or "nan") for v in a[1:]] == pytest.approx(
                [float(v or "nan") for v in b[1:]], abs=2e-5, nan_ok=True
            )
