"""Edges that read and write files: robot files, encoder logs, trajectories."""
