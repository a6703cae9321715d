"""The cross-references of the source's docstrings name what exists.

A role ``:func:``, ``:class:``, ``:meth:``, ``:data:``, ``:mod:`` or ``:exc:`` in a module of
``src/omnikin`` names its target by a full path (``omnikin.x.y``, ``~omnikin.x.y``), a path
relative to the module's package (``.schema``), or a short name that the module itself defines or
imports, or that a class of the module has (``:meth:`drive``` in a class's docstring). A renamed
or moved function leaves no reference behind that names it under its old name. (``:attr:`` is
left out: instance attributes are set in bodies, not visible on the module.)
"""

from __future__ import annotations

import builtins
import importlib
import importlib.util
import inspect
import re
from pathlib import Path

import pytest

from support.paths import SRC

PACKAGE = Path(SRC) / "omnikin"
ROLE = re.compile(r":(?:func|class|meth|data|mod|exc):`(?:[^`<]*<)?~?([\w.]+)>?`")


def module_name(path) -> str:
    parts = path.relative_to(SRC).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def lookup(dotted: str):
    """The object at ``dotted``: its longest importable module, then attributes of it (None when
    there is none)."""
    parts = dotted.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ModuleNotFoundError:
            continue
        for attr in parts[cut:]:
            if not hasattr(obj, attr) and attr not in getattr(obj, "__annotations__", {}):
                return None
            obj = getattr(obj, attr, obj)
        return obj
    return None


def resolves(module, target: str) -> bool:
    if target == "omnikin" or target.startswith("omnikin."):
        return lookup(target) is not None
    if target.startswith("."):
        package = module.__name__ if hasattr(module, "__path__") else module.__name__.rsplit(".", 1)[0]
        return lookup(f"{package}.{target.lstrip('.')}") is not None
    first, *rest = target.split(".")
    if hasattr(module, first):
        obj = getattr(module, first)
        for attr in rest:
            if not hasattr(obj, attr) and attr not in getattr(obj, "__annotations__", {}):
                return False
            obj = getattr(obj, attr)
        return True
    if not rest and any(
        inspect.isclass(c) and (hasattr(c, first) or first in getattr(c, "__annotations__", {}))
        for c in vars(module).values()
    ):
        return True  # a member of a class of the module, named in that class's docstring
    return hasattr(builtins, first) or importlib.util.find_spec(first) is not None  # Python's or a library's


def references() -> list[tuple[str, str]]:
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.name == "__main__.py":
            continue
        text = path.read_text(encoding="utf-8")
        for match in ROLE.finditer(text):
            line = text.count("\n", 0, match.start()) + 1
            found.append((f"{module_name(path)}:{line}", match.group(1)))
    return found


def test_the_walk_finds_the_references():
    """The references of the source are found (the test cannot pass on an empty list)."""
    targets = {target for _, target in references()}
    assert {"~omnikin.simulation.engine.Engine", "simulate_umbmark"} & targets
    assert len(targets) > 500


def test_a_short_reference_that_names_nothing_is_found():
    """The check refuses a name the module neither defines nor imports."""
    module = importlib.import_module("omnikin.evaluation.umbmark")
    assert resolves(module, "simulate_umbmark")
    assert not resolves(module, "run_umbmark")
    assert not resolves(module, "omnikin.simulation.motion.sample_plan")


def test_every_reference_in_a_docstring_names_what_exists():
    stale = []
    for where, target in references():
        module = importlib.import_module(where.split(":")[0])
        if not resolves(module, target):
            stale.append(f"{where}: {target}")
    assert not stale, "references to nothing:\n" + "\n".join(stale)


@pytest.mark.parametrize("target", ["omnikin.odometry.batch.batch_odometry", ".kinematic"])
def test_full_and_relative_paths_resolve(target):
    assert resolves(importlib.import_module("omnikin.simulation.engine"), target)
