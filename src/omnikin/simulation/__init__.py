"""Simulation: the :class:`~omnikin.simulation.engine.Engine` interface and the kinematic engine.

- :mod:`~omnikin.simulation.error_models`: how the robot as built and its runs differ from the
  nominal model (systematic error profiles, random noise models).
- :mod:`~omnikin.simulation.kinematic`: a plan driven by the robot as built, commanded by its
  nominal model (:func:`~omnikin.simulation.kinematic.simulate_kinematic`), and its cost.
- :mod:`~omnikin.simulation.backend`: the runtime's simulated wheel back-end
  (:class:`~omnikin.simulation.backend.SimBackend`).
- :mod:`~omnikin.simulation.engine`: :class:`~omnikin.simulation.engine.Engine`, what every
  user of a simulation holds, and :class:`~omnikin.simulation.engine.KinematicEngine`; the
  physics engine implements it in :mod:`omnikin.physics.engines`."""
