"""A pickled streaming estimator carries the version of its state: a pickle of another version
(an older omnikin kept float readings and another layout) is refused on load with one line,
instead of loading and failing later with AttributeError or ValueError, or integrating wrongly."""

from __future__ import annotations

import copy
import pickle

import pytest

from omnikin import InputError, Odometry
from omnikin.odometry.streaming import STATE_FORMAT
from support.tomasi import assert_poses_close, tomasi_poses


class PickledOdometry:
    """Pickles as an Odometry with the given state dict, as another omnikin version wrote it."""

    def __init__(self, state):
        self.state = state

    def __reduce__(self):
        return (object.__new__, (Odometry,), self.state)


def current_state(robot) -> dict:
    o = Odometry(robot)
    o.update(0.0, [0, 0, 0])
    o.update(0.01, [3, 1, 2])
    return o.__getstate__()


@pytest.mark.parametrize("version", [None, 1, STATE_FORMAT + 1, "2"])
def test_a_pickle_of_another_state_format_is_refused_on_load(tomasi, version):
    state = current_state(tomasi)
    if version is None:  # the layout before formats: no version, readings as floats, no count
        del state["_format"]
        st = state["_state"]
        state["_state"] = (st[0], st[1], st[2], st[4]) + tuple(float(v) for v in st[5:])
    else:
        state["_format"] = version
    data = pickle.dumps(PickledOdometry(state))
    with pytest.raises(InputError, match="state format") as exc:
        pickle.loads(data)
    assert "\n" not in str(exc.value)


def test_a_pickle_of_this_version_loads_and_goes_on(tomasi):
    o = Odometry(tomasi)
    o.update(0.0, [0, 0, 0])
    o.update(0.01, [3, 1, 2])
    for copied in (pickle.loads(pickle.dumps(o)), copy.deepcopy(o)):
        copied.update(0.02, [6, 2, 4])
        assert_poses_close([copied.pose], tomasi_poses([[3, 1, 2], [3, 1, 2]])[-1:])
