"""Motion: plans (paths as constant-twist segments), motion limits and wheel-speed saturation,
and the timing of a plan under those limits.

- :mod:`~omnikin.motion.plans`: segments, plans, UMBmark squares, plans from text.
- :mod:`~omnikin.motion.limits`: :class:`~omnikin.motion.limits.MotionLimits` and the
  saturation that keeps a command's direction.
- :mod:`~omnikin.motion.timing`: a plan sampled in time under limits (trapezoidal profiles).
"""
