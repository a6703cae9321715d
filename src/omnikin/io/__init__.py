"""Files: what omnikin reads and writes, each format checked at its boundary with the line and
field of a problem.

Robot files (strict YAML), tick logs, UMBmark runs and run poses, trajectories (CSV, TUM,
KITTI), ROS 2 bags (extra ``bags``), strict JSON, and the one output policy (never an input,
``--force`` to replace, atomic writes). Text is read bounded (:mod:`~omnikin.io.textfile`).
"""
