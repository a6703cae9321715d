"""The ground under the robot stays bounded, however far a run (or a hostile file) goes."""

import signal

import pytest
import viser

from omnikin.viewer.scene import MAX_GROUND, SCALE_LABELS, draw_ground, scale_step
from omnikin.viewer.serving import free_port, quiet


@pytest.mark.parametrize("extent, step", [(5.0, 0.5), (10.0, 1.0), (11.0, 2.0), (50.0, 5.0), (999.0, 100.0)])
def test_the_scale_marks_are_one_two_or_five_times_a_power_of_ten(extent, step):
    assert scale_step(extent, SCALE_LABELS) == pytest.approx(step)
    assert extent / step <= SCALE_LABELS


def _hung(signum, frame):
    raise AssertionError("draw_ground did not return within 60 s: it draws without bound")


@pytest.mark.parametrize("extent", [1e6, 1e300, float("inf"), float("nan")])
def test_a_huge_ground_is_drawn_at_most_max_ground_wide_with_ten_labels_at_once(extent):
    with quiet():
        server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    try:
        signal.signal(signal.SIGALRM, _hung)  # a safety timeout, not a pace: what is drawn is asserted below
        signal.alarm(60)
        try:
            draw_ground(server.scene, extent, 0.1)
        finally:
            signal.alarm(0)
            signal.signal(signal.SIGALRM, signal.SIG_DFL)
        grid = server.scene._handle_from_node_name["/ground"]
        assert grid.width == 2 * MAX_GROUND
        labels = [n for n in server.scene._handle_from_node_name if n.startswith("/ground/scale")]
        assert len(labels) <= SCALE_LABELS
    finally:
        with quiet():
            server.stop()
