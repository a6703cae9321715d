"""Tolerance and design studies at scale (``omnikin sweep``, extra ``sweep``): many robots as
built, each through UMBmark and calibration, for every point of a grid of factors, run on Dask.

:mod:`~omnikin.sweep.points` (a point, its key and its trials' seeds), :mod:`~omnikin.sweep.study`
(the study and the columns of its tables), :mod:`~omnikin.sweep.spec` (the study file),
:mod:`~omnikin.sweep.summary` (statistics per point and the answer to the study's question),
:mod:`~omnikin.sweep.store` (the study folder: parts written as tasks finish, resume),
:mod:`~omnikin.sweep.cluster` (Dask, embedded or on a cluster), :mod:`~omnikin.sweep.execution` (the whole study).
"""
