"""Citations a reader outside the project can follow (issue 26).

* No file cites a source paper by its internal file label (the word "seed" and
  the three-digit number of the paper's file); papers are cited by the keys of
  ``docs/references.md``, e.g. ``[Shin & Choi 1995] Table 1``.
* Every author-year key in brackets, and every bracketed text that differs from
  a defined key only in case, is defined as a heading of ``docs/references.md``;
  every Markdown link to that file points at one of its headings.
* The public names that were named after a paper's table or equation still work
  under their old names, with a ``DeprecationWarning``.
"""

import math
import os
import re
import unicodedata
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

ROOT = Path(__file__).resolve().parents[1]
REFERENCES = ROOT / "docs" / "references.md"
SKIP_DIRS = {".git", ".venv", "venv", "build", "dist", "__pycache__", ".hypothesis",
             ".pytest_cache", ".mypy_cache", ".tox", "node_modules"}

# the old label, also split over a line break, a comment or two string literals
OLD_LABEL = re.compile(r"""\bseeds?(?:[\s\-_#]|["'][\s+]*[rRbBfFuU]{0,2}["'])*0\d\d\b""", re.I)
# author-year keys: [Kim 2007], [Shin & Choi 1995], [Kyung & Sacks 2003]
AUTHOR_YEAR = re.compile(r"\[(?P<key>[A-Z][\w\-]+(?:\s*&\s*[A-Z][\w\-]+)?(?: et al\.)?"
                         r"(?:,)? (?:1[89]|20)\d\d[a-z]?)\]")
HEADING_KEY = re.compile(r"^#{2,6}\s*\[(?P<key>[^\]]+)\]\s*$", re.M)
MD_LINK = re.compile(r"\]\((?P<target>[^)\s]*references\.md(?:#[^)\s]*)?)\)|\]\((?P<local>#[^)\s]+)\)")


def source_files():
    """Every ``*.py`` and ``*.md`` file of the repository, build and tool folders skipped."""
    out = []
    for dirpath, dirnames, filenames in os.walk(ROOT):
        dirnames[:] = sorted(d for d in dirnames
                             if d not in SKIP_DIRS and not d.endswith(".egg-info"))
        for name in sorted(filenames):
            if name.endswith((".py", ".md")):
                out.append(Path(dirpath) / name)
    return out


def line_of(text, pos):
    return text.count("\n", 0, pos) + 1


def slug(heading):
    """The anchor GitHub gives a heading."""
    s = unicodedata.normalize("NFC", heading).strip().lower()
    s = "".join(c for c in s if c.isalnum() or c in " -_")
    return s.replace(" ", "-")


def defined_keys():
    text = REFERENCES.read_text(encoding="utf-8")
    return [m.group("key") for m in HEADING_KEY.finditer(text)]


def anchors():
    text = REFERENCES.read_text(encoding="utf-8")
    return {slug(m.group(1)) for m in re.finditer(r"^#{1,6}\s+(.*?)\s*$", text, re.M)}


def test_the_scan_sees_the_library():
    names = {p.relative_to(ROOT).as_posix() for p in source_files()}
    for must in ("mechanisms/linkage/error.py", "synthesis/checklist.py", "docs/fourbar.md",
                 "docs/references.md", "benchmarks/bench_fourbar.py"):
        assert must in names, must
    assert not any(n.startswith((".git/", ".venv/")) for n in names)


def test_the_old_label_pattern():
    label = "se" + "ed"          # kept apart so that this file passes its own scan
    for text in (f"{label} 003 §4.2", f"({label} 000)", f"{label.title()} 004 Table 1",
                 f"{label}-000 linkage", f"{label} 003's", f'of {label}"\n  f" 000\'s',
                 f"{label}\n# 001"):
        assert OLD_LABEL.search(text), text
    for text in (f"{label}=0", f"--{label} 7", f"({label} 0)", f"{label}ed Monte Carlo",
                 f"{label}s_from_zones", f"{label} 1, 2000 samples"):
        assert not OLD_LABEL.search(text), text


def test_no_paper_is_cited_by_its_file_label():
    hits = []
    for p in source_files():
        text = p.read_text(encoding="utf-8", errors="replace")
        for m in OLD_LABEL.finditer(text):
            ln = line_of(text, m.start())
            hits.append(f"{p.relative_to(ROOT).as_posix()}:{ln}: "
                        f"{text.splitlines()[ln - 1].strip()}")
    assert not hits, ("papers cited by file label; cite them by the keys of "
                      "docs/references.md:\n" + "\n".join(hits))


def test_references_define_the_five_papers_and_the_literature():
    keys = defined_keys()
    assert len(keys) == len(set(keys)), keys
    for key in ("Tolerance synthesis", "Shin & Choi 1995", "Choi & Bae 1999", "Kim 2007",
                "Kim 1985", "Sacks & Joskowicz 2010", "Sacks & Joskowicz 1998",
                "Kyung & Sacks 2003"):
        assert key in keys, key


def test_every_citation_key_resolves():
    keys = set(defined_keys())
    lower = {k.lower(): k for k in keys}
    bad = []
    for p in source_files():
        text = p.read_text(encoding="utf-8", errors="replace")
        where = p.relative_to(ROOT).as_posix()
        for m in AUTHOR_YEAR.finditer(text):
            if m.group("key") not in keys:
                bad.append(f"{where}:{line_of(text, m.start())}: [{m.group('key')}] "
                           f"is not defined in docs/references.md")
        for m in re.finditer(r"\[([^\[\]\n]{3,60})\]", text):
            k = m.group(1)
            if k not in keys and k.lower() in lower:
                bad.append(f"{where}:{line_of(text, m.start())}: [{k}] should read "
                           f"[{lower[k.lower()]}]")
    assert not bad, "\n".join(bad)


def test_markdown_links_to_the_references_resolve():
    targets = anchors()
    bad, n = [], 0
    for p in source_files():
        if p.suffix != ".md":
            continue
        text = p.read_text(encoding="utf-8")
        where = p.relative_to(ROOT).as_posix()
        for m in MD_LINK.finditer(text):
            if m.group("local") is not None:
                if p != REFERENCES:
                    continue
                path, anchor = REFERENCES, m.group("local")[1:]
            else:
                path_s, _, anchor = m.group("target").partition("#")
                path = (p.parent / path_s).resolve()
            n += 1
            if path != REFERENCES.resolve() and path != REFERENCES:
                bad.append(f"{where}:{line_of(text, m.start())}: {m.group(0)} is not "
                           f"docs/references.md")
            elif anchor and anchor not in targets:
                bad.append(f"{where}:{line_of(text, m.start())}: no heading #{anchor} in "
                           f"docs/references.md")
    assert n >= 10, n
    assert not bad, "\n".join(bad)


# ---------------------------------------------------------------------------
# deprecated names
# ---------------------------------------------------------------------------

def test_paper_closed_form_is_a_deprecated_alias():
    from mechanisms.linkage import FourBar, clearance_b_closed_form, paper_closed_form
    fb = FourBar.from_lengths(13.55, 8.0, 5.25, 13.3, lp=3.816, alpha=38.0,
                              assembly="crossed", unit="deg")
    beta = np.linspace(0, 2 * math.pi, 7)
    new = clearance_b_closed_form(fb, math.radians(62.935), beta)
    with pytest.warns(DeprecationWarning, match="clearance_b_closed_form"):
        old = paper_closed_form(fb, math.radians(62.935), beta)
    for name in ("beta", "omega3", "omega4", "vP"):
        assert_allclose(getattr(old, name), getattr(new, name), rtol=0, atol=0)


def test_clearance_linkage_table1_is_a_deprecated_alias():
    from mechanisms.linkage import ClearanceLinkage
    new = ClearanceLinkage.reference(ground=0.121)
    with pytest.warns(DeprecationWarning, match="ClearanceLinkage.reference"):
        old = ClearanceLinkage.table1(ground=0.121)
    assert old == new
    with pytest.warns(DeprecationWarning):
        assert ClearanceLinkage.table1(0.121, gravity=0.0) == \
            ClearanceLinkage.reference(0.121, gravity=0.0)


def test_manipulator_aliases_are_deprecated():
    from mechanisms.manipulators import (closed_form_design_indices, closed_form_forward,
                                         eq15_forward, global_design_index, table1_closed_form,
                                         two_pap, two_ppa)
    pap = two_pap(100.0, 60, unit="deg")
    ppa = two_ppa(260.0, 482.0, 300.0, 30, b=92.0, unit="deg")
    for m in (pap, ppa):
        with pytest.warns(DeprecationWarning, match="closed_form_design_indices"):
            assert table1_closed_form(m) == closed_form_design_indices(m)
    d = np.array([[10.0, 20.0], [-5.0, 3.0]])
    with pytest.warns(DeprecationWarning, match="closed_form_forward"):
        old = eq15_forward(ppa, d)
    assert_allclose(old, closed_form_forward(ppa, d), rtol=0, atol=0)
    res = global_design_index(ppa, n=5, refine=0)
    with pytest.warns(DeprecationWarning, match="ldi_max_over_min"):
        assert res.ratio_eq28 == res.ldi_max_over_min
    assert "ldi_max_over_min" in res.to_dict()

