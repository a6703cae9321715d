"""Studies of odometry: UMBmark, calibration, trajectory metrics and tolerance trials.

- :mod:`~omnikin.evaluation.run_poses`: the end poses of UMBmark runs (:class:`~omnikin.evaluation.run_poses.RunPoses`).
- :mod:`~omnikin.evaluation.umbmark`: UMBmark (Borenstein and Feng 1996): E_max,syst from the
  end poses of clockwise and counter-clockwise squares.
- :mod:`~omnikin.evaluation.calibration`: Borenstein's correction and least-squares
  calibration with identifiability.
- :mod:`~omnikin.evaluation.metrics`: ATE and RPE as evo defines them.
- :mod:`~omnikin.evaluation.pipeline`: the one study pipeline, UMBmark, calibration and UMBmark
  again, its floor and its seed layouts, driven by any engine.
- :mod:`~omnikin.evaluation.procedure`: the report's study (``omnikin umbmark``): its settings,
  seeds and cost estimate; :mod:`~omnikin.evaluation.physics_study`: the cost of that study in
  the physics engine; :mod:`~omnikin.evaluation.tolerance_trial`: a sweep's trial. Each runs the
  pipeline and differs only in what it keeps.
- :mod:`~omnikin.evaluation.order_statistics`, :mod:`~omnikin.evaluation.threshold`:
  distribution-free confidence intervals of quantiles, and where a curve crosses a target.
"""
