"""The node's parameters are documented where users look: docs/ros.md and the params module.

Every parameter the node accepts (``omnikin.ros.params.DEFAULTS``) must have a row in both
tables with its default value, and no table may list a parameter the node does not know.
"""

from __future__ import annotations

import re

import omnikin.ros.params as params
from support.paths import ROOT  # noqa: E402


def _rows(text: str) -> dict:
    """``{name: default}`` from a markdown or RST-in-docstring table: ``| `name` | default | ...``."""
    out = {}
    for m in re.finditer(r"^\|\s*``?([a-z_.]+)``?\s*\|\s*([^|]+?)\s*\|", text, flags=re.M):
        if m.group(1) != "name":
            out[m.group(1)] = m.group(2).strip("` ")
    return out


def _same(doc: str, value) -> bool:
    if isinstance(value, bool):
        return doc == str(value).lower()
    if isinstance(value, float):
        return float(doc) == value
    return doc == value


def test_every_parameter_is_documented_with_its_default():
    guide = (ROOT / "docs" / "ros.md").read_text()
    section = guide.split("\n## Parameters\n", 1)[1].split("\n## ", 1)[0]
    for source, text in (
        ("docs/ros.md, section Parameters", section),
        ("omnikin/ros/params.py docstring", params.__doc__),
    ):
        rows = _rows(text)
        assert set(rows) >= set(params.DEFAULTS), f"{source}: undocumented {set(params.DEFAULTS) - set(rows)}"
        unknown = set(rows) - set(params.DEFAULTS)
        assert not unknown, f"{source}: documents unknown parameters {unknown}"
        for key, value in params.DEFAULTS.items():
            assert _same(rows[key], value), f"{source}: {key} documented as {rows[key]!r}, default is {value!r}"
