"""Serial back-end lifecycle: a closed back-end refuses to reconnect.

Expected values are derived independently of the code under test (closed forms typed in from
the geometry, least squares computed with NumPy, or the batch odometry as reference for the
streaming estimator).
"""

from __future__ import annotations

import pytest

from omnikin import (
    OmnikinError,
    load_robot,
)

pytestmark = pytest.mark.serial


def test_reconnect_after_close_is_refused(tmp_path):
    pytest.importorskip("serial")
    from omnikin.runtime.fake_controller import FakeController
    from omnikin.runtime.serial_backend import SerialBackend

    robot = load_robot("tomasi-omni3")
    with FakeController.for_robot(robot) as fake:
        backend = SerialBackend(robot, fake.path)
        backend.close()
        with pytest.raises(OmnikinError, match="closed"):
            backend.reconnect()
