"""The robot as a kinematic chain: SE(2), wheels and their encoders, the robot and its mobility.

- :mod:`~omnikin.kinematics.se2`: poses and twists on SE(2) (exp, log, compose, inverse).
- :mod:`~omnikin.kinematics.linalg`: rank and null space with one tolerance.
- :mod:`~omnikin.kinematics.physical`: the physical fields of a robot as built (masses, sizes)
  that a physics engine needs.
- :mod:`~omnikin.kinematics.encoder`: the incremental encoder a wheel carries.
- :mod:`~omnikin.kinematics.wheels`: one wheel (type, position, radius, rollers, steering,
  encoder, motor) and its rolling constraints.
- :mod:`~omnikin.kinematics.mobility`: Campion's degrees of mobility and steerability, and the
  conditioning of a layout.
- :mod:`~omnikin.kinematics.robot`: :class:`~omnikin.kinematics.robot.Robot`, inverse and
  forward kinematics of any wheel layout.

Frames and units: ``docs/conventions.md``.
"""
