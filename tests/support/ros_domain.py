"""ROS 2 domain ids for the tests: each pytest-xdist worker draws from a slice of its own, so that
the nodes of two tests running at the same time in two workers never see each other.

A ROS 2 participant on domain D uses UDP ports 7400 + 250 D + ...; on Linux the ids 0..101 and
215..232 keep those ports clear of the ephemeral range (ROS 2 documentation, "The ROS_DOMAIN_ID").
Domain 0, every ROS 2 program's default, is left to the user's own graph. Worker k of n
(``PYTEST_XDIST_WORKER`` ``gwk``, ``PYTEST_XDIST_WORKER_COUNT`` n; without xdist k = 0, n = 1) takes
the ids whose position in that list is k modulo n; :func:`fresh_domain` hands them out in turn.
"""

from __future__ import annotations

import itertools
import os
import re

USABLE = (*range(1, 102), *range(215, 233))
"""The domain ids the tests use (0 left to the user)."""


def worker() -> tuple[int, int]:
    """(index, count) of this pytest-xdist worker; (0, 1) without xdist."""
    match = re.fullmatch(r"gw(\d+)", os.environ.get("PYTEST_XDIST_WORKER", ""))
    count = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1") or 1)
    if match is None:
        return 0, 1
    return int(match.group(1)) % max(count, 1), max(count, 1)


def worker_domains() -> tuple[int, ...]:
    """The domain ids of this worker (disjoint from every other worker's)."""
    index, count = worker()
    return USABLE[index::count]


def default_domain() -> int:
    """The worker's ``ROS_DOMAIN_ID`` for everything that does not ask for a fresh one
    (tests/conftest.py sets it in the environment of the test process and its children)."""
    return worker_domains()[0]


_domains = itertools.cycle(worker_domains()[1:] or worker_domains())


def fresh_domain() -> int:
    """The next domain id of this worker (never :func:`default_domain`), in turn: after the last
    one the first comes again, when the nodes a test started on it have long been stopped."""
    return next(_domains)
