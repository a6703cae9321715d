"""``omnikin show --json`` reports the physical fields a robot file gives, and only those."""

from __future__ import annotations

import json

from support.cli import run_cli as cli

ROBOT = """\
omnikin: 1
name: phys
physical: {mass: 2.5, com: [0, 0, 0.06]}
wheels:
  - {name: w1, type: omni, distance: 0.113, angle_deg: 0, radius: 0.04125, physical: {rows: 2, width: 0.03}}
  - {name: w2, type: omni, distance: 0.113, angle_deg: 120, radius: 0.04125}
  - {name: w3, type: omni, distance: 0.113, angle_deg: 240, radius: 0.04125}
"""


def show_json(capsys, robot):
    rc, out, err = cli(capsys, "show", robot, "--json")
    assert rc == 0 and err == "", err
    return json.loads(out)


def test_show_json_reports_the_physical_fields_given(capsys, tmp_path):
    path = tmp_path / "phys.yaml"
    path.write_text(ROBOT, encoding="utf-8")
    data = show_json(capsys, path)
    assert data["physical"] == {"mass": 2.5, "com": [0.0, 0.0, 0.06]}
    assert data["wheels"][0]["physical"] == {"rows": 2, "width": 0.03}
    assert "physical" not in data["wheels"][1] and "physical" not in data["wheels"][2]


def test_show_json_invents_no_physical_field(capsys):
    data = show_json(capsys, "omni4")
    assert "physical" not in data and all("physical" not in w for w in data["wheels"])
    tomasi = show_json(capsys, "tomasi-omni3")
    assert [w["physical"] for w in tomasi["wheels"]] == [{"rows": 2}] * 3 and "physical" not in tomasi
