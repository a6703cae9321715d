"""The rviz2 configuration shipped with the node: ``omnikin ros --rviz-config`` prints the path
of a YAML file that shows the robot (``/robot_description``, latched) in the odom frame, its
TF frames, and the odometry and ground truth in different colours."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

from support.cli import run_cli, run_entry_point
from support.paths import ROOT


def displays(config: dict) -> dict:
    """``{class name: [display, ...]}`` of the Displays of an rviz2 configuration."""
    out: dict = {}
    for d in config["Visualization Manager"]["Displays"]:
        out.setdefault(d["Class"], []).append(d)
    return out


@pytest.fixture(scope="module")
def config_path() -> Path:
    done = run_entry_point("ros", "--rviz-config")
    assert done.returncode == 0, done.stderr
    path = Path(done.stdout.strip())
    assert path.is_file() and path.suffix == ".rviz"
    return path


def test_rviz_config_shows_robot_tf_odom_and_ground_truth_in_the_odom_frame(config_path):
    config = yaml.safe_load(config_path.read_text())
    manager = config["Visualization Manager"]
    assert manager["Global Options"]["Fixed Frame"] == "odom"
    shown = displays(config)
    assert {"rviz_default_plugins/Grid", "rviz_default_plugins/TF"} <= set(shown)
    (model,) = shown["rviz_default_plugins/RobotModel"]
    assert model["Description Source"] == "Topic"
    topic = model["Description Topic"]
    assert topic["Value"] == "/robot_description"
    # the node publishes the description once, transient local: a volatile subscriber never gets it
    assert topic["Durability Policy"] == "Transient Local" and topic["Reliability Policy"] == "Reliable"
    odometry = {d["Topic"]["Value"]: d for d in shown["rviz_default_plugins/Odometry"]}
    assert set(odometry) == {"/odom", "/ground_truth"}
    colours = {t: d["Shape"]["Color"] for t, d in odometry.items()}
    assert colours["/odom"] != colours["/ground_truth"]
    for d in [*shown["rviz_default_plugins/Odometry"], model]:
        assert d["Enabled"] is True


def test_rviz_config_is_package_data(config_path):
    """Installed with the package (pyproject's package-data), beside the node it belongs to."""
    import omnikin.ros

    assert config_path.parent == Path(omnikin.ros.__file__).resolve().parent
    text = (ROOT / "pyproject.toml").read_text()
    section = text.split("\n[tool.setuptools.package-data]\n", 1)[1].split("\n[", 1)[0]
    line = re.search(r'^"omnikin\.ros" = \[(.*)\]$', section, flags=re.M)
    assert line and f'"{config_path.name}"' in line.group(1), section


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["ros", "diff-drive", "--rviz-config"], "not with ROBOT"),
        (["ros", "--rviz-config", "--seed", "3"], "not with --seed"),
        (["ros", "--rviz-config", "--backend", "serial"], "not with --backend serial"),
        (["ros"], "needs ROBOT"),
    ],
)
def test_rviz_config_alone_and_robot_otherwise(capsys, argv, says):
    rc, out, err = run_cli(capsys, *argv)
    assert rc == 2 and out == ""
    assert says in err and len(err.strip().splitlines()) == 1, err


def test_rviz_config_draws_the_path_followed_and_its_reference_point(config_path):
    shown = displays(yaml.safe_load(config_path.read_text()))
    (path,) = shown["rviz_default_plugins/Path"]
    # reference_path is published once per path, transient local: a volatile subscriber misses it
    assert path["Topic"]["Value"] == "/reference_path" and path["Topic"]["Durability Policy"] == "Transient Local"
    (pose,) = shown["rviz_default_plugins/Pose"]
    assert pose["Topic"]["Value"] == "/reference" and pose["Enabled"] is True
