"""Benchmarks of odometry (core layer 7): UMBmark, calibration."""
