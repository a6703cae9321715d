"""JSON omnikin prints or writes is strict JSON (RFC 8259): no NaN, no Infinity, whatever the input.

Every ``--json`` command is run and its output parsed by a parser that refuses the three
constants Python's json module would otherwise write (``NaN``, ``Infinity``, ``-Infinity``).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from omnikin.cli.main import main
from omnikin.errors import NonFiniteValueError
from omnikin.io.jsonfile import to_json, write_json


def strict(text: str):
    def refuse(constant):
        raise AssertionError(f"non-standard JSON constant {constant}")

    return json.loads(text, parse_constant=refuse)


def json_of(capsys, *argv):
    rc = main([str(a) for a in argv] + ["--json"])
    out, err = capsys.readouterr()
    assert rc == 0, err
    return strict(out)


# --- the helper --------------------------------------------------------------------------------------------
def test_non_finite_values_name_their_field():
    doc = {"rpe": {"rotation_deg": {"std": math.nan}}, "speeds": [1.0, -math.inf]}
    with pytest.raises(NonFiniteValueError, match=r"field rpe\.rotation_deg\.std is nan") as info:
        to_json(doc)
    assert info.value.field == "rpe.rotation_deg.std"
    with pytest.raises(NonFiniteValueError, match=r"field speeds\[1\] is -inf"):
        to_json({"speeds": np.array([1.0, -np.inf])})


def test_documented_fields_become_null_and_numpy_is_plain():
    doc = {"calibration": {"improvement": math.inf}, "count": np.int64(3), "ok": np.bool_(True), "xs": np.arange(3.0)}
    assert strict(to_json(doc, nullable=["improvement"])) == {
        "calibration": {"improvement": None},
        "count": 3,
        "ok": True,
        "xs": [0.0, 1.0, 2.0],
    }
    assert strict(to_json(doc, nullable=["calibration.improvement"]))["calibration"]["improvement"] is None
    with pytest.raises(NonFiniteValueError):
        to_json(doc, nullable=["other"])


def test_json_files_follow_the_output_policy(tmp_path):
    out = tmp_path / "r.json"
    write_json(out, {"a": 1.5})
    assert strict(out.read_text()) == {"a": 1.5}
    with pytest.raises(Exception, match="--force"):
        write_json(out, {"a": 2})
    with pytest.raises(NonFiniteValueError):
        write_json(out, {"a": math.nan}, force=True)
    assert strict(out.read_text()) == {"a": 1.5}  # nothing written on error


# --- every --json command -------------------------------------------------------------------------------------
def test_presets_show_ik_fk(capsys):
    assert len(json_of(capsys, "presets")) >= 9
    for name in ("tomasi-omni3", "ackermann", "diff-drive"):
        json_of(capsys, "show", name)
    json_of(capsys, "ik", "ackermann", "1", "0", "0.3")
    json_of(capsys, "ik", "diff-drive", "0.5", "0.1", "0", "--allow-infeasible")
    json_of(capsys, "fk", "omni4", "1", "-2", "3", "-4")
    json_of(capsys, "fk", "synchro", "1", "1", "1", "--steer-deg", "0", "0", "0")


def test_odometry(capsys, tmp_path):
    log = tmp_path / "log.csv"
    log.write_text("t,w1,w2,w3\n0,0,0,0\n0.1,5,-3,2\n0.2,10,-6,4\n")
    json_of(capsys, "odometry", "tomasi-omni3", log, "-o", tmp_path / "out.csv")


def test_bags_and_metrics(capsys, tmp_path):
    pytest.importorskip("rosbags")
    bag = tmp_path / "sim.bag"
    json_of(capsys, "simulate", "diff-drive", "--path", "square ccw rotate 1", "--rate", "20", "--bag", bag)
    json_of(capsys, "bag", "odometry", "diff-drive", bag, "-o", tmp_path / "odom.bag")
    assert (
        main(
            [
                "bag",
                "export",
                str(bag),
                "--topic",
                "/ground_truth",
                "--format",
                "tum",
                "-o",
                str(tmp_path / "truth.tum"),
            ]
        )
        == 0
    )
    assert (
        main(["bag", "export", str(bag), "--topic", "/odom", "--format", "tum", "-o", str(tmp_path / "odom.tum")]) == 0
    )
    capsys.readouterr()
    doc = json_of(capsys, "metrics", tmp_path / "truth.tum", tmp_path / "odom.tum", "--align")
    assert doc["ate"]["translation"]["rmse"] >= 0
    # a single associated pose pair: no RPE pairs; still strict JSON (or a one-line error), never NaN
    one = tmp_path / "one.tum"
    one.write_text("0 0 0 0 0 0 0 1\n")
    rc = main(["metrics", str(one), str(one), "--json"])
    out, err = capsys.readouterr()
    if rc == 0:
        strict(out)
    else:
        assert rc == 2 and err.count("\n") == 1 and "NaN" not in out


def test_umbmark_analyze(capsys, tmp_path):
    runs = tmp_path / "m.csv"
    runs.write_text("direction,x_abs,y_abs,x_calc,y_calc\ncw,0.01,0.02,0,0\nccw,-0.03,0.01,0,0\n")
    json_of(capsys, "umbmark", "analyze", runs, "--robot", "diff-drive")
