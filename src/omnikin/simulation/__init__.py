"""Simulation (core layer 6): motion plans and limits, error models, simulated runs, and the
:class:`~omnikin.simulation.engine.Engine` interface with the kinematic engine."""
