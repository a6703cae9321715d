"""docs/architecture.md is true to the package: every source module is in its tables, and the
tables list the packages in the order of the layer contract of pyproject.toml.

The tables of "What each module holds" name each module by its path under ``src/omnikin/`` in
backticks (a protocol sub-package such as ``runtime/protocol/`` may be named as a folder). Read
from top to bottom, the packages of the rows climb the contract's layers (``[tool.importlinter]``,
the contract of type ``layers`` without containers, whose list runs from the top layer down):
a row never names a package of a layer below one named in an earlier row.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10: tomli, which import-linter brings there
    import tomli as tomllib

from support.paths import ROOT

PACKAGE = ROOT / "src" / "omnikin"
DOC = ROOT / "docs" / "architecture.md"


def source_modules(package: Path) -> list[str]:
    """Every module of the package as its path under ``package`` (``kinematics/robot.py``),
    package ``__init__`` files left out."""
    return sorted(p.relative_to(package).as_posix() for p in package.rglob("*.py") if p.name != "__init__.py")


def module_tables(text: str) -> list[list[str]]:
    """The backticked paths of each table row of the "What each module holds" section, row by row."""
    start = text.index("## What each module holds")
    end = text.index("\n## ", start + 1)
    rows = []
    for line in text[start:end].splitlines():
        cells = line.split("|")
        if len(cells) > 3 and not set(cells[2].strip()) <= {"-"} and cells[2].strip() != "modules":
            rows.append(re.findall(r"`([^`]+)`", cells[2]))
    return rows


def documented(module: str, named: set[str]) -> bool:
    """Whether ``module`` is named, or (below a package's own folder) its folder is."""
    if module in named:
        return True
    parts = module.split("/")
    return any("/".join(parts[:k]) + "/" in named for k in range(2, len(parts)))


def layer_ranks(pyproject: Path) -> dict[str, int]:
    """Each package of the layer contract to its rank from the bottom (0 = the lowest layer)."""
    contracts = tomllib.loads(pyproject.read_text(encoding="utf-8"))["tool"]["importlinter"]["contracts"]
    (layers,) = [c["layers"] for c in contracts if c["type"] == "layers" and "containers" not in c]
    ranks = {}
    for rank, layer in enumerate(reversed(layers)):
        for name in re.split(r"[|:]", layer):
            ranks[name.strip().removeprefix("omnikin.")] = rank
    return ranks


def package_of(path: str) -> str:
    return path.split("/")[0].removesuffix(".py")


def order_problems(rows: list[list[str]], ranks: dict[str, int]) -> list[str]:
    problems = []
    highest = ("", -1)
    for row in rows:
        for path in row:
            name = package_of(path)
            if name not in ranks:
                continue
            if ranks[name] < highest[1]:
                problems.append(f"{path} (layer {name}) is listed after {highest[0]}, a higher layer")
            elif ranks[name] > highest[1]:
                highest = (name, ranks[name])
    return problems


def test_every_source_module_is_in_the_architecture_tables():
    named = {path for row in module_tables(DOC.read_text(encoding="utf-8")) for path in row}
    missing = [m for m in source_modules(PACKAGE) if not documented(m, named) and m != "_version.py"]
    assert missing == [], f"docs/architecture.md does not list {missing}"


def test_the_tables_list_the_packages_in_the_order_of_the_layer_contract():
    rows = module_tables(DOC.read_text(encoding="utf-8"))
    assert order_problems(rows, layer_ranks(ROOT / "pyproject.toml")) == []


def test_every_layer_of_the_contract_has_a_row():
    rows = module_tables(DOC.read_text(encoding="utf-8"))
    listed = {package_of(path) for row in rows for path in row}
    assert set(layer_ranks(ROOT / "pyproject.toml")) - listed == set()


def test_a_missing_module_and_a_row_out_of_order_are_found(tmp_path):
    package = tmp_path / "pkg"
    (package / "low").mkdir(parents=True)
    (package / "low" / "a.py").write_text("")
    (package / "low" / "b.py").write_text("")
    (package / "high.py").write_text("")
    text = (
        "## What each module holds\n\n| package | modules | what |\n|---|---|---|\n"
        "| high | `high.py` | top |\n| low | `low/a.py` | bottom |\n\n## Next\n"
    )
    rows = module_tables(text)
    named = {path for row in rows for path in row}
    assert [m for m in source_modules(package) if not documented(m, named)] == ["low/b.py"]
    assert order_problems(rows, {"high": 1, "low": 0}) == ["low/a.py (layer low) is listed after high, a higher layer"]
    assert order_problems(list(reversed(rows)), {"high": 1, "low": 0}) == []
