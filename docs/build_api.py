"""Build the API reference of ``cspace``, ``mechanisms`` and ``synthesis`` as HTML.

    pip install ".[docs]"
    python docs/build_api.py --out out/api

One page per public module (a name without a leading ``_`` at every level),
docstrings read as numpy style; open ``out/api/index.html``.  The pages are
built, not kept in git (``out/`` is ignored).  ``tests/test_api_docs.py`` builds them into a
temporary folder and checks that every public module has its page and that
pdoc warned about nothing.

pdoc, given a package, documents only the submodules the package names in
``__all__`` (when it has one); this script hands pdoc every public module by
name, so each gets its page whatever its package exports.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import pkgutil
import sys
from pathlib import Path

#: The packages documented, with every public module and subpackage in them.
PACKAGES = ("cspace", "mechanisms", "synthesis")


def public_modules(packages=PACKAGES) -> list:
    """Dotted names of the packages and of every public module below them."""
    out = []
    for top in packages:
        pkg = importlib.import_module(top)
        out.append(top)
        out += [m.name for m in pkgutil.walk_packages(pkg.__path__, f"{top}.")
                if not any(part.startswith("_") for part in m.name.split("."))]
    return sorted(out)


def page_of(module: str, out) -> Path:
    """The HTML file pdoc writes for ``module`` below ``out``."""
    return Path(out).joinpath(*module.split(".")).with_suffix(".html")


def build(out, modules=None) -> list:
    """Render ``modules`` (default: :func:`public_modules`) into the folder
    ``out``; returns the module names rendered."""
    from pdoc import doc, render

    modules = public_modules() if modules is None else list(modules)
    out = Path(out)
    render.configure(docformat="numpy", show_source=True, search=True)
    docs = {name: doc.Module.from_name(name) for name in modules}
    for name, mod in docs.items():
        page = page_of(name, out)
        page.parent.mkdir(parents=True, exist_ok=True)
        page.write_text(render.html_module(mod, docs), encoding="utf-8")
    (out / "index.html").write_text(render.html_index(docs), encoding="utf-8")
    (out / "search.js").write_text(render.search_index(docs), encoding="utf-8")
    return modules


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out/api", help="output folder (default out/api)")
    args = ap.parse_args(argv)
    if importlib.util.find_spec("pdoc") is None:
        print("pdoc is not installed: pip install 'cspace-tolerance[docs]'", file=sys.stderr)
        return 2
    mods = build(args.out)
    print(f"wrote {len(mods)} module pages to {args.out} (open {Path(args.out) / 'index.html'})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
