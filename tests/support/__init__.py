"""Helpers shared by the tests and the benchmarks: browsers, servers, simulated chips and their
firmware, Dask clusters, ROS domains, the repository paths and the ways to run omnikin.

Imported as ``support.<module>``: pytest puts ``tests/`` on the path (``pythonpath`` in
pyproject.toml), and ``benchmarks/support`` is a link to this folder, so a benchmark run as
``python3 benchmarks/bench_x.py`` imports the same modules."""
