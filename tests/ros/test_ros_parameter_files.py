"""ROS parameter files and options: bad files refused with one line, exponent floats, serial-only
options with the simulated back-end.

Regression tests of the review findings, grouped here by module. Expected values are derived
independently of the code under test (closed forms typed in from the geometry, least squares
computed with NumPy, or the batch odometry as reference for the streaming estimator).
"""

from __future__ import annotations

import pytest

from conftest import run_cli
from omnikin import (
    OmnikinError,
)


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
