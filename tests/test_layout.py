"""The package's layers, checked on its source: the data flows one way, geometry → model
→ interactions → solvers → io → applications, and private names stay in their package.

A module may import from its own layer or a lower one, never from a higher one; a
private name (a module or attribute whose name starts with ``_``) may be imported only
by modules inside the package that holds it.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import masonry_fdem

ROOT = Path(masonry_fdem.__file__).parent

#: the layers, lowest first; a module belongs to the longest prefix that names it
#: ("" is the package's own __init__, the top: it re-exports the public API)
LAYERS = (
    # (io.checkpoint: files and signals only, below the solvers that write checkpoints)
    ("_compat", "constants", "checks", "io.checkpoint"),
    ("geometry",),
    ("parallel",),
    ("materials",),
    ("model",),
    ("interactions.protocol", "interactions.search", "interactions._sums"),
    ("interactions.contact",),
    ("interactions.joints",),
    ("interactions.disks",),
    ("interactions.anchors",),
    ("interactions",),
    ("solvers",),
    ("io",),
    ("assessment",),
    ("cli", "precompile", ""),
)


def module_name(path: Path) -> str:
    """'interactions.contact.penalty' for .../interactions/contact/penalty.py; a
    package's __init__ is the package."""
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def layer_of(name: str) -> int:
    best, level = -1, None
    for k, prefixes in enumerate(LAYERS):
        for p in prefixes:
            hit = name == p if p == "" else (name == p or name.startswith(p + "."))
            if hit and len(p) > best:
                best, level = len(p), k
    if level is None:
        raise LookupError(f"module {name!r} is in no layer: add it to LAYERS")
    return level


def is_package(name: str) -> bool:
    return (ROOT.joinpath(*name.split(".")) / "__init__.py").exists() if name else True


def is_module(name: str) -> bool:
    return is_package(name) or ROOT.joinpath(*name.split(".")).with_suffix(".py").exists()


def imports_of(source: str, importer: str) -> list[tuple[str, str | None, int]]:
    """(module, imported name or None, line) of every import of the package's own
    modules, relative imports resolved, with names 'masonry_fdem.' stripped."""
    out = []
    pkg = importer if is_package(importer) else importer.rpartition(".")[0]
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name == "masonry_fdem" or a.name.startswith("masonry_fdem."):
                    out.append((a.name.removeprefix("masonry_fdem").lstrip("."), None,
                                node.lineno))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".") if pkg else []
                base = base[: len(base) - (node.level - 1)]
                mod = ".".join([*base, *([node.module] if node.module else [])])
            elif node.module == "masonry_fdem" or node.module.startswith("masonry_fdem."):
                mod = node.module.removeprefix("masonry_fdem").lstrip(".")
            else:
                continue
            for a in node.names:
                out.append((mod, a.name, node.lineno))
    return out


def problems_of(source: str, importer: str) -> list[str]:
    """What is wrong with the imports of one module's source."""
    found = []
    mine = layer_of(importer)
    for mod, name, line in imports_of(source, importer):
        sub = f"{mod}.{name}".lstrip(".") if name else None
        target = sub if sub is not None and is_module(sub) else mod
        if layer_of(target) > mine:
            found.append(f"{importer}:{line} imports {target or 'masonry_fdem'} from a higher "
                         "layer")
        # the package that owns a private module, or a private name of a module
        parts = target.split(".") if target else []
        owner = None
        for k, part in enumerate(parts):
            if part.startswith("_"):
                owner = ".".join(parts[:k])
                break
        if owner is None and name is not None and name.startswith("_"):
            owner = target if is_package(target) else target.rpartition(".")[0]
        if owner is not None and not (owner == "" or importer == owner
                                      or importer.startswith(owner + ".")):
            found.append(f"{importer}:{line} imports the private {name or target} of "
                         f"{owner or 'masonry_fdem'}")
    return found


def test_no_module_imports_upwards_or_another_packages_private_names():
    files = sorted(ROOT.rglob("*.py"))
    assert len(files) > 40
    found = []
    for path in files:
        found += problems_of(path.read_text(), module_name(path))
    print(f"\n{len(files)} modules checked against {len(LAYERS)} layers")
    assert not found, "\n".join(found)


@pytest.mark.parametrize("importer, source, expect", [
    ("model.model", "from masonry_fdem.solvers import _kernels as K", ["higher", "private"]),
    ("interactions.contact.penalty", "from masonry_fdem.interactions.disks import Disks",
     ["higher"]),
    ("interactions.disks.disk_block",
     "from masonry_fdem.interactions.contact import _kernels", ["private"]),
    ("assessment.assess", "from masonry_fdem import Model", ["higher"]),
    ("assessment.assess", "from masonry_fdem.model import Model", []),
    ("interactions.disks.disks", "from . import _kernels", []),
    ("interactions.disks.disks", "from ..contact.penalty import _sync", ["private"]),
    ("geometry.layout", "import masonry_fdem._compat", []),
])
def test_the_checker_finds_what_it_should(importer, source, expect):
    found = problems_of(source, importer)
    assert len(found) == len(expect), found
    for msg, word in zip(found, expect, strict=True):
        assert word in msg
