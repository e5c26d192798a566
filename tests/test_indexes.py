"""Every package's ``__init__`` docstring is its index: each public module
(and subpackage) begins a line of it, with a one-line description on that line
or indented on the next."""

import importlib
import pkgutil
import re

import pytest

TOP = ("cspace", "mechanisms", "synthesis")


def _packages():
    out = []
    for top in TOP:
        pkg = importlib.import_module(top)
        out.append(top)
        out += [m.name for m in pkgutil.walk_packages(pkg.__path__, f"{top}.")
                if m.ispkg and not any(p.startswith("_") for p in m.name.split("."))]
    return sorted(out)


def public_modules(package: str) -> list:
    """The public modules and subpackages directly inside ``package``."""
    pkg = importlib.import_module(package)
    return sorted(m.name for m in pkgutil.iter_modules(pkg.__path__)
                  if not m.name.startswith("_"))


def indexed(doc: str, package: str, name: str) -> bool:
    """Does a line of ``doc`` begin with ``name`` (or ``package.name``, either
    in double backticks) followed by a description on that line, or with the
    description indented on the next line?"""
    lines = doc.splitlines()
    head = re.compile(rf"^(\s*)(``)?({re.escape(package)}\.)?{re.escape(name)}(``)?(\s+\S|\s*$)")
    for i, line in enumerate(lines):
        m = head.match(line)
        if not m:
            continue
        if m.group(5).strip():
            return True
        nxt = lines[i + 1] if i + 1 < len(lines) else ""
        if nxt.strip() and len(nxt) - len(nxt.lstrip()) > len(m.group(1)):
            return True
    return False


def test_the_walk_finds_the_packages_and_their_modules():
    pk = _packages()
    assert {"cspace", "cspace.batch", "mechanisms", "mechanisms.linkage", "synthesis"} <= set(pk)
    assert {"accuracy", "plotting", "batch"} <= set(public_modules("cspace"))
    assert not [m for m in public_modules("synthesis") if m.startswith("_")]


def test_indexed_needs_a_line_that_starts_with_the_name_and_describes_it():
    doc = "Index\n-----\nfourbar     FourBar value\nclearance\n``pkg.plan``\n    The plan.\n"
    assert indexed(doc, "pkg", "fourbar")
    assert indexed(doc, "pkg", "plan")
    assert not indexed(doc, "pkg", "clearance")      # no description
    assert not indexed(doc, "pkg", "four")           # a prefix is not the name
    assert not indexed("the fourbar module", "pkg", "fourbar")   # prose, not an index line


@pytest.mark.parametrize("package", _packages())
def test_package_docstring_indexes_every_public_module(package):
    doc = importlib.import_module(package).__doc__ or ""
    missing = [m for m in public_modules(package) if not indexed(doc, package, m)]
    init = f"{package.replace('.', '/')}/__init__.py"
    assert not missing, (f"{init}: its docstring does not index {missing}; add a line "
                         f"'name   one-line description' for each")
