"""A Dask preload for the sweep tests only: the worker process that loads it (``dask worker
--preload``) reports the omnikin version in ``OMNIKIN_TEST_FAKE_VERSION`` instead of its own, as a
worker with another omnikin installed would (``dask_cluster.start_worker``)."""

from __future__ import annotations

import os

import omnikin
import omnikin._version

omnikin._version.__version__ = os.environ["OMNIKIN_TEST_FAKE_VERSION"]
omnikin.__version__ = omnikin._version.__version__
