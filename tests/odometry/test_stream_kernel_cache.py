"""The compiled streaming kernels are kept in a bounded cache: a program that builds estimators
for ever new configurations (a calibration sweep, a fuzzer) does not grow without bound (a
cache that kept every kernel and its linecache source would hold 64 MB for 2000 slightly
different robots). An estimator keeps working after its kernels left the cache."""

from __future__ import annotations

import linecache

from omnikin import Odometry
from omnikin.odometry import _stream_kernel as kernel
from support.tomasi import assert_poses_close, tomasi_poses


def kernel_lines() -> int:
    return sum(1 for name in linecache.cache if str(name).startswith("<omnikin-kernel-"))


def test_the_kernel_cache_and_its_source_lines_stay_bounded(tomasi):
    first = Odometry(tomasi, max_wheel_speed=1.0)
    first.update(0.0, [0, 0, 0])
    for k in range(kernel.CACHE_SIZE + 40):
        Odometry(tomasi, max_wheel_speed=2.0 + k)  # a new bound: a new kernel source
        assert len(kernel._COMPILED) <= kernel.CACHE_SIZE
        assert kernel_lines() <= kernel.CACHE_SIZE
    assert first._kernels.source not in kernel._COMPILED  # dropped, least recently built
    rows = [[0, 0, 0], [1, 0, 0], [2, 1, 0], [3, 1, 1]]
    poses = [first.pose] + [first.update(0.01 * k, rows[k]) for k in range(1, 4)]
    assert_poses_close(poses, tomasi_poses([[1, 0, 0], [1, 1, 0], [1, 0, 1]]))


def test_a_kernel_in_use_is_kept_while_others_come_and_go(tomasi):
    """Building an estimator of a cached configuration moves it to the back of the queue."""
    keep = Odometry(tomasi, max_wheel_speed=7.5)
    for k in range(kernel.CACHE_SIZE + 10):
        Odometry(tomasi, max_wheel_speed=100.0 + k)
        Odometry(tomasi, max_wheel_speed=7.5)
    assert keep._kernels.source in kernel._COMPILED
    name = kernel._COMPILED[keep._kernels.source][0]
    assert linecache.getline(name, 1).startswith("def move(")
