"""Wheel odometry: encoder readings -> wheel angle increments -> body increments -> poses.

- :mod:`~omnikin.odometry.encoders`: counters, wrap-around and the plausibility rules that
  turn an impossible increment into an error instead of a wrong pose.
- :mod:`~omnikin.odometry.integration`: body increments composed on SE(2) (exact exponential;
  Euler and midpoint for comparison).
- :mod:`~omnikin.odometry.batch`: odometry over whole arrays of samples.
- :mod:`~omnikin.odometry.streaming`: the streaming estimator
  (:class:`~omnikin.odometry.streaming.Odometry`), one sample at a time, and
  :mod:`~omnikin.odometry._stream_kernel`, the per-configuration code it generates.
"""
