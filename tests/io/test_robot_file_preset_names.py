"""One rule names a robot (docs/conventions.md, "Naming a robot"): a preset name given as a
string is the shipped preset, whatever the current folder holds; a robot file is named by a path
(``./omni4``, ``omni4.yaml``, a ``Path``) or by any other name. A file or folder of the current
folder called like a preset never replaces it: one warning line says how to name it."""

from __future__ import annotations

import json
import shutil
import subprocess
import warnings
from pathlib import Path

import pytest

from omnikin import load_robot
from omnikin.errors import PresetShadowWarning
from omnikin.io.robot_file import is_preset_spec, robot_file_of
from omnikin.presets import PRESET_NAMES, preset_path
from support.cli import run_entry_point

SHIPPED_WHEELS = {"omni4": 4, "mecanum4": 4, "tomasi-omni3": 3, "diff-drive": 3}
"""Wheel counts of some presets, read off their files in src/omnikin/presets."""


def omnikin(cwd: Path, *argv: str) -> subprocess.CompletedProcess:
    return run_entry_point(*argv, cwd=cwd)


@pytest.fixture
def folder(tmp_path, monkeypatch):
    """The current folder holds a file 'omni4' (a copy of tomasi-omni3) and a folder 'mecanum4'."""
    shutil.copy(preset_path("tomasi-omni3"), tmp_path / "omni4")
    (tmp_path / "mecanum4").mkdir()
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_a_preset_name_is_the_preset_even_when_a_file_has_its_name(folder):
    with pytest.warns(PresetShadowWarning, match=r"'omni4' is the preset omni4, not the file 'omni4'.*\./omni4"):
        robot = load_robot("omni4")
    assert robot.name == "omni4" and len(robot.wheels) == SHIPPED_WHEELS["omni4"]
    with pytest.warns(PresetShadowWarning, match=r"not the folder 'mecanum4'.*write \./mecanum4"):
        assert len(load_robot("mecanum4").wheels) == SHIPPED_WHEELS["mecanum4"]


def test_a_path_names_the_file(folder):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning: the file is named as a path
        for spec in ("./omni4", str(folder / "omni4"), Path("omni4")):
            robot = load_robot(spec)
            assert robot.name == "tomasi-omni3" and len(robot.wheels) == 3, spec
        robot = load_robot("diff-drive")  # no such file here: the preset, silently
        assert len(robot.wheels) == SHIPPED_WHEELS["diff-drive"]


def test_the_rule_in_one_function():
    for name in PRESET_NAMES:
        assert is_preset_spec(name) and robot_file_of(name) is None
    for spec in ("./omni4", "omni4.yaml", "robots/omni4", "my-robot", "omni4/"):
        assert not is_preset_spec(spec) and robot_file_of(spec) == spec
    assert robot_file_of(Path("omni4")) == "omni4" and robot_file_of(None) is None


def test_presets_lists_the_shipped_files_whatever_the_folder_holds(folder):
    proc = omnikin(folder, "presets", "--json")
    assert proc.returncode == 0 and proc.stderr == ""
    listed = {p["name"]: p["wheels"] for p in json.loads(proc.stdout)}
    assert list(listed) == list(PRESET_NAMES)
    for name, wheels in SHIPPED_WHEELS.items():
        assert listed[name] == wheels


@pytest.mark.parametrize("name, kind", [("omni4", "file"), ("mecanum4", "folder")])
def test_commands_use_the_preset_and_warn_once(folder, name, kind):
    proc = omnikin(folder, "show", name, "--json")
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["name"] == name
    assert proc.stderr == (
        f"omnikin: warning: '{name}' is the preset {name}, not the {kind} '{name}' in the current folder "
        f"(write ./{name} to load that {kind})\n"
    )


def test_the_file_is_read_when_named_as_a_path(folder):
    proc = omnikin(folder, "show", "./omni4", "--json")
    assert proc.returncode == 0 and proc.stderr == ""
    assert json.loads(proc.stdout)["name"] == "tomasi-omni3"
    proc = omnikin(folder, "show", "./mecanum4")
    assert proc.returncode == 2 and "./mecanum4: is a directory, not a robot file" in proc.stderr


def test_a_report_folder_named_like_the_preset_does_not_break_the_next_run(tmp_path):
    argv = ("umbmark", "diff-drive", "-o", "diff-drive", "--runs", "1", "--rate", "20", "--no-calibrate", "--json")
    first = omnikin(tmp_path, *argv)
    assert first.returncode == 0 and first.stderr == "", first.stderr
    second = omnikin(tmp_path, *argv)
    assert second.returncode == 0, second.stderr
    assert second.stderr.count("\n") == 1 and "'diff-drive' is the preset diff-drive" in second.stderr
    assert json.loads(second.stdout)["robot"]["name"] == "diff-drive"
    assert (tmp_path / "diff-drive" / "result.json").is_file()
