"""The API reference (``docs/build_api.py``, pdoc) builds: every public module
gets its page, and pdoc warns about nothing (a module that does not import, an
annotation or a docstring it cannot read)."""

import importlib.util
import warnings
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _build_api():
    spec = importlib.util.spec_from_file_location("build_api", ROOT / "docs" / "build_api.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_public_modules_are_found_and_private_ones_left_out():
    mods = _build_api().public_modules()
    for must in ("cspace", "cspace.argcheck", "cspace.batch.margins", "mechanisms.linkage.error",
                 "mechanisms.spatial.solve", "synthesis.verify", "synthesis.cli.plotting"):
        assert must in mods
    assert not [m for m in mods if any(p.startswith("_") for p in m.split("."))]


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    pytest.importorskip("pdoc")
    api = _build_api()
    out = tmp_path_factory.mktemp("api")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mods = api.build(out)
    return api, out, mods, caught


def test_every_public_module_has_a_page(built):
    api, out, mods, _ = built
    assert set(mods) == set(api.public_modules())
    missing = [m for m in mods if not api.page_of(m, out).is_file()]
    assert not missing
    assert (out / "index.html").is_file()
    # the pages hold the docstrings, not just the names
    page = api.page_of("cspace.argcheck", out).read_text(encoding="utf-8")
    assert "getseed" in page and "numpy.random.Generator" in page
    page = api.page_of("cspace.batch.kernels", out).read_text(encoding="utf-8")
    assert "KernelStack" in page


def test_pdoc_warns_about_nothing(built):
    _, _, _, caught = built
    ours = [w for w in caught
            if "pdoc" in Path(w.filename).parts
            or Path(w.filename).resolve().is_relative_to(ROOT)]
    assert not ours, "\n".join(f"{Path(w.filename).name}:{w.lineno}: {w.message}" for w in ours)
