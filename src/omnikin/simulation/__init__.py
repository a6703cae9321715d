"""Simulation (core layer 6): motion plans and limits, error models, simulated runs."""
