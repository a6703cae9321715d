"""Wheel odometry: encoder readings -> wheel angle increments -> body increments -> poses.

- :mod:`~omnikin.odometry.samples`: timestamps, non-finite values, and the first problem of a
  block of samples with its rank.
- :mod:`~omnikin.odometry.counters`: readings as exact numbers and the increment of a counter
  that wraps.
- :mod:`~omnikin.odometry.plausibility`: the speed and change-of-speed rules that turn an
  impossible increment into an error instead of a wrong pose.
- :mod:`~omnikin.odometry.increments`: encoder readings -> wheel angle increments over a block,
  every rule applied.
- :mod:`~omnikin.odometry.integration`: body increments composed on SE(2) (exact exponential;
  Euler and midpoint for comparison).
- :mod:`~omnikin.odometry.batch`: odometry over whole arrays of samples.
- :mod:`~omnikin.odometry.streaming`: the streaming estimator
  (:class:`~omnikin.odometry.streaming.Odometry`), one sample at a time, and
  :mod:`~omnikin.odometry._stream_kernel`, the per-configuration code it generates.
"""
