"""Robot runtime, free of ROS: base controller, wheel back-ends, serial protocol.

- :mod:`~omnikin.runtime.base`: :class:`~omnikin.runtime.base.BaseRuntime`, command in -> wheel
  commands out, wheel measurements in -> odometry out;
- :mod:`~omnikin.runtime.command`: velocity commands (validation, timeout, acceleration limit,
  saturation); :mod:`~omnikin.runtime.goal`: driving to a goal pose;
  :mod:`~omnikin.runtime.teleop`: held keys to a target twist;
- :mod:`~omnikin.runtime.backends`: the wheel back-end interface;
  :mod:`~omnikin.runtime.serial_backend`: wheel controllers on serial links;
  :mod:`~omnikin.runtime.fake_controller`: a simulated wheel controller on a pseudo-terminal;
- :mod:`~omnikin.runtime.protocol`: the wheel-controller protocol.

The ROS 2 node (:mod:`omnikin.ros`) is a thin shell around :class:`~omnikin.runtime.base.BaseRuntime`.
"""
