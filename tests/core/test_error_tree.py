"""Every exception omnikin raises on purpose is in one tree: defined in ``omnikin/errors.py``,
exported from ``omnikin``, and drawn in the module docstring of ``omnikin.errors``."""

from __future__ import annotations

import ast
import builtins
import inspect
import re
from pathlib import Path

import omnikin
import omnikin.errors

SRC = Path(omnikin.__file__).parent
ERRORS = SRC / "errors.py"
BUILTIN_EXCEPTIONS = {
    name for name, value in vars(builtins).items() if isinstance(value, type) and issubclass(value, BaseException)
}


def _base_name(node: ast.expr) -> str | None:
    """``ValueError`` for ``ValueError``, ``InputError`` for ``errors.InputError``."""
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        return node.attr
    return None


def exception_classes(sources: dict[str, str]) -> list[tuple[str, str]]:
    """(file, class name) of every class in ``sources`` (file -> Python source) that derives,
    directly or through other classes of ``sources``, from a built-in exception or warning;
    nested classes included. Read from the syntax tree: nothing is imported."""
    classes = []
    for file, text in sources.items():
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.ClassDef):
                bases = {b for b in map(_base_name, node.bases) if b is not None}
                classes.append((file, node.name, bases))
    known = set(BUILTIN_EXCEPTIONS)
    found: set[tuple[str, str]] = set()
    grew = True
    while grew:
        grew = False
        for file, name, bases in classes:
            if (file, name) not in found and bases & known:
                found.add((file, name))
                known.add(name)
                grew = True
    return sorted(found)


def package_sources() -> dict[str, str]:
    return {str(p.relative_to(SRC)): p.read_text(encoding="utf-8") for p in sorted(SRC.rglob("*.py"))}


def errors_classes() -> dict[str, type]:
    return {
        name: value
        for name, value in vars(omnikin.errors).items()
        if inspect.isclass(value) and value.__module__ == "omnikin.errors"
    }


def drawn_tree() -> dict[str, tuple[str, list[str]]]:
    """The tree of the docstring of ``omnikin.errors``: class -> (parent, the ``also`` bases),
    read from its literal block (``├── Name (also A, B): ...``, four columns per level)."""
    doc = omnikin.errors.__doc__
    assert doc is not None
    block = doc.split("::\n", 1)[1].strip("\n").split("\n\n", 1)[0]  # the indented block after "::"
    tree: dict[str, tuple[str, list[str]]] = {}
    stack: list[str] = []
    for line in block.splitlines():
        line = line[4:]
        m = re.match(r"^((?:│   |    )*)(├── |└── )?(\w+)(?: \(also ([\w, ]+)\))?", line)
        assert m, f"not a line of the tree: {line!r}"
        depth = len(m[1]) // 4 + (1 if m[2] else 0)
        del stack[depth:]
        if depth:
            also = [a.strip() for a in m[4].split(",")] if m[4] else []
            tree[m[3]] = (stack[depth - 1], also)
        stack.append(m[3])
    return tree


def test_the_walk_finds_exceptions_through_aliases_attributes_and_nesting():
    sources = {
        "a.py": "class A(ValueError): pass\nclass NotOne(dict): pass\n",
        "b.py": "from . import errors\nclass B(errors.A): pass\ndef f():\n    class C(B): pass\n",
        "c.py": "class W(UserWarning): pass\nclass S(BaseException): pass\n",
    }
    assert exception_classes(sources) == [("a.py", "A"), ("b.py", "B"), ("b.py", "C"), ("c.py", "S"), ("c.py", "W")]


def test_every_public_exception_is_defined_in_errors_py():
    outside = [
        f"{file}: {name}"
        for file, name in exception_classes(package_sources())
        if file != "errors.py" and not name.startswith("_")
    ]
    assert outside == [], "exception classes belong in omnikin/errors.py"


def test_the_walk_sees_every_class_of_errors_py():
    walked = {name for file, name in exception_classes(package_sources()) if file == "errors.py"}
    assert walked == set(errors_classes())


def test_every_exception_is_exported_from_the_package():
    for name, cls in errors_classes().items():
        assert name in omnikin.__all__, name
        assert getattr(omnikin, name) is cls


def test_the_docstring_draws_every_class_with_its_bases():
    tree = drawn_tree()
    classes = errors_classes()
    assert set(tree) - {"Exception", "BaseException", "UserWarning"} == set(classes)
    for name, cls in classes.items():
        parent, also = tree[name]
        assert parent == cls.__bases__[0].__name__, name
        assert also == [b.__name__ for b in cls.__bases__[1:]], name


def test_branches_are_the_built_in_kinds_callers_catch():
    assert issubclass(omnikin.BagError, ValueError) and issubclass(omnikin.ProtocolError, ValueError)
    assert issubclass(omnikin.LinkLostError, RuntimeError) and issubclass(omnikin.WorkerMismatch, RuntimeError)
    assert issubclass(omnikin.DivergedError, RuntimeError) and issubclass(omnikin.PhysicsError, omnikin.OmnikinError)
    assert issubclass(omnikin.OutputError, OSError)
    assert not issubclass(omnikin.Terminated, Exception)
    assert issubclass(omnikin.PresetShadowWarning, UserWarning)
