"""ROS parameter files and options: bad files refused with one line, exponent floats, serial-only
options with the simulated back-end.

Expected values are derived independently of the code under test (closed forms typed in from
the geometry, least squares computed with NumPy, or the batch odometry as reference for the
streaming estimator).
"""

from __future__ import annotations

import pytest

from omnikin import (
    OmnikinError,
)
from support.cli import run_cli
from support.paths import omnikin_env


@pytest.mark.parametrize(
    "content, fragment",
    [
        (b"\xff\xfe", "not a UTF-8 text file"),
        (b"omnikin_base: {ros__parameters: 5}\n", "ros__parameters must be a mapping"),
        (b"publish_rate: 0.0\n", "publish_rate"),
        (b"reject_above: -1.0\n", "reject_above"),
        (b"bogus: 1\n", "unknown parameter 'bogus'"),
    ],
)
def test_ros_parameter_files_bad(tmp_path, content, fragment):
    from omnikin.ros.params import load_params

    p = tmp_path / "p.yaml"
    p.write_bytes(content)
    with pytest.raises(OmnikinError, match=fragment):
        load_params(p)


def test_ros_parameter_exponent_floats(tmp_path):
    """YAML 1.1 reads 2e-4 as a string; the documented default must load as a number."""
    from omnikin.ros.params import load_params

    p = tmp_path / "p.yaml"
    p.write_text("wheel_slip: 2e-4\nlinear:\n  x:\n    max_velocity: 5E-1\n")
    values = load_params(p)
    assert values["wheel_slip"] == 2e-4 and values["linear.x.max_velocity"] == 0.5


def test_ros_serial_only_options_with_sim_backend(capsys):
    rc, _, err = run_cli(capsys, "ros", "tomasi-omni3", "--port", "/dev/ttyUSB0")
    assert rc == 2 and "apply only to --backend serial" in err


@pytest.mark.parametrize(
    "backend, options, message",
    [
        (
            "physics",
            ["--noise", "none", "--seed", "3"],
            "noise (--noise) 'none': the physics engine has no random error model (slip comes from the wheels' roller "
            "contact, its encoders count whole ticks); drop --noise",
        ),
        ("physics", ["--baud", "115200"], "--baud apply only to --backend serial"),
        ("serial", ["--errors", "none", "--seed", "3"], "--errors, --seed apply only to --backend sim or physics"),
        ("serial", ["--true-robot", "x.yaml"], "--true-robot apply only to --backend sim or physics"),
        (
            "physics",
            ["--errors", "none", "--true-robot", "x.yaml"],
            "ros: argument --true-robot: not allowed with argument --errors (see omnikin ros --help)",
        ),
    ],
)
def test_ros_backends_refuse_the_options_of_other_backends(capsys, backend, options, message):
    rc, _, err = run_cli(capsys, "ros", "tomasi-omni3", "--backend", backend, *options)
    assert rc == 2 and err.strip() == f"omnikin: error: {message}"


def test_ros_true_robot_of_other_wheels_is_refused_before_the_node_starts(capsys, tmp_path):
    """--true-robot builds the robot as built of both simulated back-ends: a file whose wheels
    are not the nominal robot's is refused in one line naming the difference."""
    rc, _, err = run_cli(capsys, "ros", "tomasi-omni3", "--backend", "physics", "--true-robot", "diff-drive")
    assert rc == 2 and len(err.strip().splitlines()) == 1 and "diff-drive" in err, err


def test_ros_physics_backend_without_mujoco_names_the_physics_extra(tmp_path):
    """In a clean interpreter where importing mujoco fails: one line naming the extra."""
    import subprocess
    import sys

    pytest.importorskip("rclpy", reason="the node checks rclpy before the back-end (extra ros)")
    code = (
        "import sys\n"
        "class Block:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] == 'mujoco':\n"
        "            raise ImportError(f'No module named {name!r}')\n"
        "sys.meta_path.insert(0, Block())\n"
        "from omnikin.cli.main import main\n"
        "sys.exit(main(['ros', 'tomasi-omni3', '--backend', 'physics']))\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], env=omnikin_env(), cwd=tmp_path, capture_output=True, text=True, timeout=60
    )
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2, proc.stderr
    assert len(lines) == 1 and 'pip install "omnikin[physics]"' in lines[0], proc.stderr
