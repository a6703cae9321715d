"""Physics simulation of any robot file (extra ``physics``: MuJoCo).

- :mod:`~omnikin.physics.description`: the robot as a physical body (chassis, wheels, rollers,
  joints, motors), derived from the wheel layout with documented defaults; pure data and NumPy;
- :mod:`~omnikin.physics.mjcf`: MuJoCo's XML model (MJCF) of a description, as text;
- :mod:`~omnikin.physics.simulator`: :class:`~omnikin.physics.simulator.PhysicsSim`, the model
  stepped in MuJoCo with ramped wheel commands, encoders and ground truth;
- :mod:`~omnikin.physics.backend`: :class:`~omnikin.physics.backend.PhysicsBackend`, the
  runtime's wheel back-end on top of it (a drop-in for the kinematic
  :class:`~omnikin.simulation.backend.SimBackend`).
- :mod:`~omnikin.physics.validity`: what the engine accepts (a model that resolves the robot at
  every accepted time step), refused before any simulation in one line;
- :mod:`~omnikin.physics.cost`: what a physics run will take, before it starts;
- :mod:`~omnikin.physics.run`: a plan driven in the physics engine
  (:func:`~omnikin.physics.run.simulate_physics`) and the ways it did not drive as commanded;
- :mod:`~omnikin.physics.engines`: :class:`~omnikin.physics.engines.PhysicsEngine`, all of it as
  an :class:`~omnikin.simulation.engine.Engine`, and :func:`~omnikin.physics.engines.engine_named`,
  the one factory of engines by name;
- :mod:`~omnikin.physics.urdf`, :mod:`~omnikin.physics.link_frames`,
  :mod:`~omnikin.physics.joint_motion`: the URDF of a description, where each of its links is,
  and the joints no sensor measures moved as the body motion implies (for ``/tf`` and the viewer);
- :mod:`~omnikin.physics.interactive`: the window of ``omnikin sim`` (MuJoCo's viewer, driven
  from the keyboard).

Only the simulator and the window import ``mujoco``; the description and the MJCF text work
without it.
"""
