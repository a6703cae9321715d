"""Physics simulation of any robot file (extra ``physics``: MuJoCo).

- :mod:`~omnikin.physics.description`: the robot as a physical body (chassis, wheels, rollers,
  joints, motors), derived from the wheel layout with documented defaults; pure data and NumPy;
- :mod:`~omnikin.physics.mjcf`: MuJoCo's XML model (MJCF) of a description, as text;
- :mod:`~omnikin.physics.simulator`: :class:`~omnikin.physics.simulator.PhysicsSim`, the model
  stepped in MuJoCo with ramped wheel commands, encoders and ground truth;
- :mod:`~omnikin.physics.backend`: :class:`~omnikin.physics.backend.PhysicsBackend`, the
  runtime's wheel back-end on top of it (a drop-in for the kinematic
  :class:`~omnikin.simulation.backend.SimBackend`).
- :mod:`~omnikin.physics.engines`: :class:`~omnikin.physics.engines.PhysicsEngine`, all of it as
  an :class:`~omnikin.simulation.engine.Engine`, and :func:`~omnikin.physics.engines.engine_named`,
  the one factory of engines by name.

Only the simulator and the window import ``mujoco``; the description and the MJCF text work
without it.
"""
