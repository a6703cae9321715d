"""The public names document their arguments in numpydoc sections that match their signatures.

Public: every function and class in ``omnikin.__all__`` or ``omnikin.api.__all__`` (exceptions
aside: their tree is documented in :mod:`omnikin.errors`), the public functions of a module
exported there (``omnikin.se2``), and the public methods that such a class defines itself. A
numpydoc section is a title underlined by as many dashes (``Parameters`` / ``----------``); in
``Parameters`` and ``Attributes`` an entry starts at the section's indentation as
``name : type`` (``x, y : float`` documents two).

- a method is documented by its own docstring or, when it has none, by that of the method it
  implements (``inspect.getdoc``: ``KinematicEngine.problems`` by ``Engine.problems``), so an
  implementation that adds nothing to its interface is documented once, by the interface;
- a function or method with arguments has a ``Parameters`` section that names exactly its
  arguments, in the order of its signature;
- a function or method with arguments that returns something (its annotation is not ``None``)
  has ``Returns`` (one without arguments says what it gives in its summary line);
- a class has ``Parameters`` naming exactly the arguments of its constructor (one a caller builds:
  ``Robot``, ``Wheel``, ``Odometry``), or ``Attributes`` (a result the library builds); every
  entry of ``Attributes`` is an attribute of the class, a field, declared by an annotation in the
  class's body (an interface's ``name: ClassVar[str]``), or set as ``self.NAME = ...`` in the
  class's source (a renamed field leaves no stale entry behind).
"""

from __future__ import annotations

import dataclasses
import inspect
import re

import pytest

import omnikin
import omnikin.api


def sections(doc: str | None) -> dict[str, list[str]]:
    """The numpydoc sections of ``doc`` by title, each the lines below its underline."""
    lines = inspect.cleandoc(doc or "").splitlines()
    starts = [
        i
        for i in range(len(lines) - 1)
        if lines[i].strip()
        and set(lines[i + 1].strip()) == {"-"}
        and len(lines[i + 1].strip()) == len(lines[i].strip())
    ]
    out = {}
    for k, i in enumerate(starts):
        end = starts[k + 1] if k + 1 < len(starts) else len(lines)
        out[lines[i].strip()] = lines[i + 2 : end]
    return out


def entry_names(body: list[str]) -> list[str]:
    """The names of a Parameters or Attributes section's entries, in order."""
    indent = min((len(line) - len(line.lstrip()) for line in body if line.strip()), default=0)
    names = []
    for line in body:
        if line.strip() and len(line) - len(line.lstrip()) == indent:
            names += [name.strip() for name in line.split(" : ")[0].split(",")]
    return names


def public_objects() -> list[tuple[str, object]]:
    found = {}
    for module in (omnikin, omnikin.api):
        for name in module.__all__:
            obj = getattr(module, name)
            if isinstance(obj, type) and issubclass(obj, BaseException):
                continue
            if inspect.isfunction(obj) or inspect.isclass(obj):
                found[name] = obj
            elif inspect.ismodule(obj):
                for attr, member in vars(obj).items():
                    if not attr.startswith("_") and inspect.isfunction(member) and member.__module__ == obj.__name__:
                        found[f"{name}.{attr}"] = member
    return sorted(found.items())


def callables() -> list[tuple[str, object]]:
    """The public functions, and the public methods the public classes define themselves."""
    out = []
    for name, obj in public_objects():
        if inspect.isfunction(obj):
            out.append((name, obj))
            continue
        for attr, member in vars(obj).items():
            if not attr.startswith("_") and inspect.isfunction(member):
                out.append((f"{name}.{attr}", member))
    return out


def arguments(function) -> list[str]:
    params = list(inspect.signature(function).parameters.values())
    return [p.name for p in params if p.name != "self"]


def test_the_checked_names_cover_the_exports():
    """The walk finds the entry points and the core classes (it cannot pass on an empty list)."""
    names = {name for name, _ in public_objects()}
    assert {"simulate", "run_umbmark", "batch_odometry", "load_robot", "Robot", "Wheel", "Odometry"} <= names
    assert {"se2.exp", "se2.log", "se2.compose"} <= names
    methods = {name for name, _ in callables()}
    assert {"Robot.ik", "Robot.fk", "Odometry.update", "UMBmarkReport.write"} <= methods


@pytest.mark.parametrize("name, function", callables(), ids=lambda v: v if isinstance(v, str) else "")
def test_parameters_section_names_the_signature(name, function):
    args = arguments(function)
    found = sections(inspect.getdoc(function))
    if not args:
        assert "Parameters" not in found, f"{name} takes no arguments but documents some"
        return
    assert "Parameters" in found, f"{name}{inspect.signature(function)} has no Parameters section"
    assert entry_names(found["Parameters"]) == args, f"{name}: Parameters do not match the signature"


@pytest.mark.parametrize("name, function", callables(), ids=lambda v: v if isinstance(v, str) else "")
def test_a_result_is_documented_in_returns(name, function):
    if inspect.signature(function).return_annotation in (None, "None") or not arguments(function):
        return  # a method without arguments says what it returns in its summary line (``figures``)
    assert "Returns" in sections(inspect.getdoc(function)), f"{name} returns a value but has no Returns section"


@pytest.mark.parametrize(
    "name, cls",
    [(n, c) for n, c in public_objects() if inspect.isclass(c)],
    ids=lambda v: v if isinstance(v, str) else "",
)
def test_class_documents_its_constructor_or_its_attributes(name, cls):
    found = sections(cls.__doc__)
    assert "Parameters" in found or "Attributes" in found, f"{name} has neither Parameters nor Attributes"
    if "Parameters" in found:
        assert entry_names(found["Parameters"]) == list(inspect.signature(cls).parameters), (
            f"{name}: Parameters do not match the constructor {inspect.signature(cls)}"
        )
    if "Attributes" in found:
        fields = {f.name for f in dataclasses.fields(cls)} if dataclasses.is_dataclass(cls) else set()
        assigned = set(re.findall(r"self\.([A-Za-z]\w*)\s*(?::[^=\n]*)?=[^=]", inspect.getsource(cls)))
        for attribute in entry_names(found["Attributes"]):
            declared = attribute in inspect.get_annotations(cls)
            known = attribute in fields or attribute in assigned or declared or hasattr(cls, attribute)
            assert known, f"{name} documents no attribute {attribute!r}"


def names_in_docs() -> list[str]:
    """Every dotted name under ``omnikin`` that docs/*.md and README.md write
    (``omnikin.odometry.counters.wrap_scalar``), but the keys of a bag's metadata
    (``omnikin.seed``) and file names (``omnikin.rviz``)."""
    from support.paths import ROOT

    texts = [p.read_text(encoding="utf-8") for p in sorted((ROOT / "docs").rglob("*.md"))]
    texts.append((ROOT / "README.md").read_text(encoding="utf-8"))
    found = set()
    for text in texts:
        found.update(re.findall(r"(?<![\w./-])omnikin(?:\.[A-Za-z_]\w*)+", text))
    return sorted(found)


def resolved(name: str):
    """The object ``name`` names: its longest importable module, then attributes of it; None
    when no module of omnikin and no attribute of it has that name."""
    import importlib

    parts = name.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ModuleNotFoundError as exc:
            if exc.name is not None and exc.name.startswith("omnikin"):
                continue
            raise
        for attr in parts[cut:]:
            if not hasattr(obj, attr):
                return None
            obj = getattr(obj, attr)
        return obj
    return None


METADATA_KEYS = {"omnikin.robot", "omnikin.seed", "omnikin.engine", "omnikin.noise", "omnikin.path", "omnikin.rate"}
"""Keys of a bag's metadata that docs/bags.md names (not modules)."""


def documented_objects() -> list[tuple[str, object]]:
    """The functions and classes that the docs name by their dotted path and the exports do not
    cover (a user imports them as the docs write them), exceptions aside."""
    exported = {id(obj) for _, obj in public_objects()}
    out = {}
    for name in names_in_docs():
        obj = resolved(name)
        if isinstance(obj, type) and issubclass(obj, BaseException):
            continue
        if (inspect.isfunction(obj) or inspect.isclass(obj)) and id(obj) not in exported:
            out[name] = obj
    return sorted(out.items())


def test_every_dotted_name_in_the_docs_exists():
    """A module, function, class or constant the docs name by its dotted path is there (a moved
    or renamed one leaves no stale path behind)."""
    names = names_in_docs()
    assert "omnikin.odometry.counters.wrap_scalar" in names  # the walk finds the names
    missing = [n for n in names if n not in METADATA_KEYS and n != "omnikin.rviz" and resolved(n) is None]
    assert not missing, f"docs name what does not exist: {missing}"


@pytest.mark.parametrize("name, obj", documented_objects(), ids=lambda v: v if isinstance(v, str) else "")
def test_what_the_docs_name_documents_its_arguments(name, obj):
    """A function or class the docs name has the sections of an exported one: Parameters naming
    its signature and Returns (a function), Parameters or Attributes (a class)."""
    found = sections(inspect.getdoc(obj) if inspect.isfunction(obj) else obj.__doc__)
    if inspect.isclass(obj):
        assert "Parameters" in found or "Attributes" in found, f"{name} has neither Parameters nor Attributes"
        if "Parameters" in found:
            assert entry_names(found["Parameters"]) == list(inspect.signature(obj).parameters), name
        return
    args = arguments(obj)
    if args:
        assert "Parameters" in found and entry_names(found["Parameters"]) == args, f"{name}: Parameters"
        if inspect.signature(obj).return_annotation not in (None, "None"):
            assert "Returns" in found, f"{name} returns a value but has no Returns section"
