"""Studies of odometry: UMBmark, calibration, trajectory metrics and tolerance trials.

- :mod:`~omnikin.evaluation.run_poses`: the end poses of UMBmark runs (:class:`RunPoses`).
- :mod:`~omnikin.evaluation.umbmark`: UMBmark (Borenstein and Feng 1996): E_max,syst from the
  end poses of clockwise and counter-clockwise squares.
- :mod:`~omnikin.evaluation.calibration`: Borenstein's correction and least-squares
  calibration with identifiability.
- :mod:`~omnikin.evaluation.metrics`: ATE and RPE as evo defines them.
- :mod:`~omnikin.evaluation.procedure`, :mod:`~omnikin.evaluation.physics_study`,
  :mod:`~omnikin.evaluation.tolerance_trial`: UMBmark, calibration and UMBmark again, with seeds,
  cost estimates, confidence intervals and the floor of the engine.
- :mod:`~omnikin.evaluation.order_statistics`, :mod:`~omnikin.evaluation.threshold`:
  distribution-free confidence intervals of quantiles, and where a curve crosses a target.
"""
