"""The two ways the tests run omnikin's command line: in this process (:func:`run_cli`, output
captured by pytest's ``capsys``) and as a user does, in a fresh process (:func:`run_entry_point`)."""

from __future__ import annotations

import subprocess
import sys

from support.paths import omnikin_env


def run_entry_point(*argv, cwd=None, timeout: float = 120) -> subprocess.CompletedProcess:
    """Run ``omnikin ARGV`` as a user does, in a fresh process importing this checkout's omnikin
    (:func:`omnikin_env`) from any working folder ``cwd``; text output captured; ``timeout`` [s]
    guards against a hang."""
    return subprocess.run(
        [sys.executable, "-m", "omnikin.cli.main", *[str(a) for a in argv]],
        cwd=cwd,
        capture_output=True,
        text=True,
        env=omnikin_env(),
        timeout=timeout,
    )


def run_cli(capsys, *argv):
    """Run ``omnikin`` in this process: ``(exit status, stdout, stderr)``. ``main`` returns a
    status for everything, usage errors and ``--help`` included: anything it raises fails the test."""
    from omnikin.cli.main import main

    rc = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return rc, out, err
