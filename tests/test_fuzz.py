"""Fuzz suite: mutated pair files, model files and DXF drawings through the
public loaders, the analysis and a short defect test.

Each case must end in a clean result or an exception from the project's error
tree (:class:`cspace.errors.CSpaceError`), within :data:`CASE_SECONDS`, with no
NaN in any output.  Mutations: wrong types, missing and unknown keys, NaN, inf,
huge and tiny numbers, deep nesting, long strings, open and self-crossing
loops, zero-radius arcs, tangent contacts, hostile expressions, and damaged
text (truncation, stray characters).

The default run draws :data:`CASES` examples (about 1,100) from the fixed seed
of the ``repeatable`` profile (tests/conftest.py); the ``slow`` tests draw
twenty times as many.  ``FUZZ_SUMMARY=path`` writes the outcome counts as JSON.
"""

from __future__ import annotations

import atexit
import copy
import json
import math
import os
import signal
import tempfile
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cspace.errors import CSpaceError

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "docs" / "examples" / "flat_follower_cam.json"

#: Longest a single case may take, s (a typical case takes well under 0.5 s).
CASE_SECONDS = 20.0
#: Examples per document kind in the default run (the slow tests: 20 times).
CASES = {"pair": 900, "model": 700, "dxf": 400}
SLOW_FACTOR = 20

OUTCOMES: Counter = Counter()


def _write_summary():
    path = os.environ.get("FUZZ_SUMMARY")
    if path and OUTCOMES:
        Path(path).write_text(json.dumps(dict(sorted(OUTCOMES.items())), indent=1))


atexit.register(_write_summary)

# ---------------------------------------------------------------- hostile values

DEEP = object()        # placeholder: a deeply nested list
HOSTILE_VALUES = [
    None, True, False, 0, -1, 1, 0.0, -0.0, 5e-324, 1e-320, 1e-300, 1e-15, 1e15, 1e100,
    1e300, -1e300, 1.7976931348623157e308, math.nan, math.inf, -math.inf, 10 ** 400,
    10 ** 4000, "", " ", "x", "a" * 100_000, "NaN", "1e999", [], {}, [0], [1, 2, 3],
    [math.nan, 0], [1e308, 1e308], {"type": "arc"}, {"type": "line"}, "\x00", "é" * 50,
    DEEP,
]
HOSTILE_EXPRESSIONS = [
    "__import__('os').system('echo pwned')", "().__class__.__bases__[0].__subclasses__()",
    "open('/etc/passwd').read()", "9**9**9**9", "10**10**10", "1/0", "sqrt(-1)", "log(0)",
    "1e308*10", "(" * 400 + "1" + ")" * 400, "(" * 5000 + "1" + ")" * 5000, "x" * 5000,
    "lambda: 0", "[i for i in range(10**9)]", "rb.__class__", "exec('1')",
    "rb" + "+rb" * 3000, "globals()", "import os", "rb; rb", "rb\n+1", "'abc'",
    "f'{rb}'", "(lambda: 1)()", "rb if rb else 0", "nan", "inf", "-inf", "1e-320",
    "asin(2)", "acos(rb)", "tan(pi/2)", "exp(1000)", "2**1023*2", "rb*1e308",
    "sqrt(rb - 1e9)", "pi - pi", "0*rb", "rb - rb", "1e-300 * rb", "cos", "atan2(0, 0)",
]
SPECIAL_TEXT = ["NaN", "Infinity", "-Infinity", "1e999", "9" * 5000, "[" * 3000, "{" * 50,
                "\x00", "\ufeff"]


def _deep(depth):
    v = 0
    for _ in range(depth):
        v = [v]
    return v


def _positions(doc):
    """Every (container, key) in a JSON document, parents first."""
    out = []
    stack = [doc]
    while stack:
        c = stack.pop()
        items = c.items() if isinstance(c, dict) else enumerate(c)
        for k, v in items:
            out.append((c, k))
            if isinstance(v, (dict, list)):
                stack.append(v)
    return out


@st.composite
def mutated_text(draw, base: dict, expressions: bool, specials=()):
    """A base document after 1 to 3 mutations, as JSON text (maybe damaged)."""
    doc = copy.deepcopy(base)
    for _ in range(draw(st.integers(1, 3))):
        if specials and draw(st.integers(0, 4)) == 0:
            try:
                draw(st.sampled_from(specials))(doc)
            except (KeyError, TypeError, IndexError, AttributeError, OverflowError):
                pass     # an earlier mutation removed what it changes (or made it
                #          an integer too large to add a float to)
            continue
        pos = _positions(doc)
        if not pos:
            break
        c, k = pos[draw(st.integers(0, len(pos) - 1))]
        old = c[k]
        kind = draw(st.sampled_from(["value", "value", "number", "delete", "unknown",
                                     "nest", "expr", "dup", "swap"]))
        if kind == "value":
            v = draw(st.sampled_from(HOSTILE_VALUES))
            # deep nesting is spliced into the text (json.dumps itself recurses)
            # a copy: later mutations must not change the list of hostile values
            c[k] = (f"__deep_{draw(st.sampled_from([3, 60, 500, 3000]))}__" if v is DEEP
                    else copy.deepcopy(v))
        elif kind == "number" and isinstance(old, (int, float)) and not isinstance(old, bool):
            f = draw(st.sampled_from([1 + 1e-12, 1 - 1e-12, 1e6, 1e-6, -1.0, 0.0, 1e-12,
                                      1e12, 2.0, 0.5]))
            try:
                c[k] = old * f if math.isfinite(old * f) else old
            except OverflowError:      # an integer of thousands of digits
                pass
        elif kind == "delete":
            del c[k]
        elif kind == "unknown" and isinstance(c, dict):
            c[draw(st.sampled_from(["extra", "__class__", "", "x" * 300]))] = 1
        elif kind == "nest":
            c[k] = _deep(draw(st.sampled_from([1, 2, 50])))
            if isinstance(c[k], list):
                inner = c[k]
                while isinstance(inner[0], list):
                    inner = inner[0]
                inner[0] = old
        elif kind == "expr" and expressions:
            c[k] = draw(st.sampled_from(HOSTILE_EXPRESSIONS))
        elif kind == "dup" and isinstance(c, list):
            c.insert(k, copy.deepcopy(old))
        elif kind == "swap" and isinstance(c, list) and len(c) > 1:
            j = draw(st.integers(0, len(c) - 1))
            c[k], c[j] = c[j], c[k]
    text = json.dumps(doc, allow_nan=True)
    for depth in (3, 60, 500, 3000):
        text = text.replace(f'"__deep_{depth}__"', "[" * depth + "0" + "]" * depth)
    damage = draw(st.integers(0, 9))
    if damage == 0:
        text = text[:draw(st.integers(0, len(text)))]
    elif damage == 1:
        i = draw(st.integers(0, len(text)))
        text = text[:i] + draw(st.sampled_from(SPECIAL_TEXT + list("{}[],:\"\\"))) + text[i:]
    return text


# ---------------------------------------------------------------- base documents

def _base_model() -> dict:
    return json.loads(EXAMPLE.read_text())


def _base_pair() -> dict:
    from cspace.io import pair_to_dict
    from mechanisms.userfile import load_model
    d = pair_to_dict(load_model(EXAMPLE).build())
    return json.loads(json.dumps(d))


def _pair_specials():
    def open_loop(d):
        d["parts"][0]["loops"][0][0]["end"][0] += 1e-3

    def open_loop_tiny(d):
        d["parts"][0]["loops"][0][0]["end"][0] += 1e-9

    def self_crossing(d):
        seg = d["parts"][1]["loops"][0]
        seg[0]["end"], seg[2]["end"] = seg[2]["end"], seg[0]["end"]

    def zero_radius(d):
        d["parts"][0]["loops"][0][1]["radius"] = 0

    def tiny_radius(d):
        d["parts"][0]["loops"][0][1]["radius"] = 1e-300

    def tangent(d):
        # the follower's face on the base circle (radius 20) at q2 = 0
        for seg in d["parts"][1]["loops"][0]:
            for key in ("start", "end"):
                seg[key][1] = 20.0 if seg[key][1] == 21.0 else seg[key][1]

    def overlap(d):
        for seg in d["parts"][1]["loops"][0]:
            for key in ("start", "end"):
                seg[key][1] -= 10.0

    def far_centre(d):
        d["parts"][0]["axis"]["center"] = [1.7e99, 0.0]

    def tiny_sweep(d):
        a = d["parts"][0]["loops"][0][1]
        a["end_angle"] = a["start_angle"] + 1e-15

    return [open_loop, open_loop_tiny, self_crossing, zero_radius, tiny_radius, tangent,
            overlap, far_centre, tiny_sweep]


def _model_specials():
    def tangent(d):
        for p in d["parameters"]:
            if p["name"] == "face":
                p["nominal"] = 20.0
        d["q2_start"] = [0.0]

    def zero_tol(d):
        for p in d["parameters"]:
            p["tol"] = 0.0

    def huge_tol(d):
        d["parameters"][2]["tol"] = 1e6

    def zero_radius(d):
        d["parameters"][3]["nominal"] = 0.0

    def deep_let(d):
        d["let"] = [{"name": f"v{i}", "value": f"v{i - 1} + 1" if i else "1"}
                    for i in range(3000)]

    def self_ref(d):
        d["let"].append({"name": "loop", "value": "loop + 1"})

    return [tangent, zero_tol, huge_tol, zero_radius, deep_let, self_ref]


# ---------------------------------------------------------------- running a case

class _Timeout(Exception):
    pass


def _alarm(signum, frame):
    raise _Timeout()


def _bounded(fn):
    """Run ``fn`` with a wall-clock bound (SIGALRM; the main thread only)."""
    if not hasattr(signal, "setitimer"):
        return fn()
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, CASE_SECONDS)
    try:
        return fn()
    except _Timeout:
        pytest.fail(f"case took longer than {CASE_SECONDS} s")
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def _no_nan(obj, what):
    """JSON output without NaN or inf (dumps refuses them)."""
    from cspace.io import dumps
    try:
        dumps(obj)
    except ValueError as e:
        pytest.fail(f"{what} holds a non-finite number: {e}")


def _analyze(obj, defect: bool):
    """The analysis as ``cspace-tol analyze`` runs it, and a short defect test."""
    from cspace.freespace import Status
    from mechanisms.analysis import model_cspaces
    from mechanisms.models import Model
    spaces = model_cspaces(obj, accuracy="fast")
    for cs in spaces:
        _no_nan(cs.to_dict(), "cspace.json")
        lo1, hi1, lo2, hi2 = cs.window
        q = np.column_stack([np.linspace(lo1, hi1, 7), np.linspace(lo2, hi2, 7)])
        assert all(isinstance(s, Status) for s in cs.classify(q))
    if isinstance(obj, Model):
        from cspace.defects import is_defective, reference
        from cspace.zones import contact_zones
        ref = reference(obj, "fast")
        for i, (cs, f) in enumerate(zip(ref.spaces, ref.faces)):
            _no_nan(contact_zones(cs, obj, i, faces=[f]).to_dict(), "zones.json")
        for s in ref.sims:
            _no_nan(s.to_dict(), "simulation.json")
        if defect:
            r = is_defective(obj, obj.nominal + obj.tol, ref=ref)
            assert isinstance(r.defective, (bool, np.bool_))
            # an unmeasurable deviation is inf by design; NaN never
            assert not math.isnan(r.max_deviation) and not math.isnan(r.d)
    return "clean"


_TMP = Path(tempfile.mkdtemp(prefix="cspace-fuzz-"))


def _run(kind, load, text, tmp=_TMP, defect=False):
    path = tmp / f"case.{'dxf' if kind == 'dxf' else 'json'}"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")

    def case():
        try:
            obj = load(path)
        except CSpaceError as e:
            assert str(e).strip(), "an error without a message"
            return f"load: {type(e).__name__}"
        try:
            return _analyze(obj, defect)
        except CSpaceError as e:
            assert str(e).strip(), "an error without a message"
            return f"analyze: {type(e).__name__}"

    outcome = _bounded(case)
    OUTCOMES[f"{kind} {outcome}"] += 1
    OUTCOMES[f"{kind} cases"] += 1


# ---------------------------------------------------------------- the tests

_PAIR = _base_pair()
_MODEL = _base_model()
_FUZZ = dict(deadline=None, database=None,
             suppress_health_check=list(HealthCheck))


def _load_pair(p):
    from cspace.io import load_pair
    return load_pair(p)


def _load_model(p):
    from mechanisms.userfile import load_model
    return load_model(p)


def _pair_case(text, tmp_path_factory):
    _run("pair", _load_pair, text, _TMP)


def _model_case(text, defect, tmp_path_factory):
    _run("model", _load_model, text, _TMP, defect=defect)


# a mutated file may name any length unit: loading it warns, as documented
@pytest.mark.filterwarnings("ignore::cspace.io.UnitWarning")
@settings(max_examples=CASES["pair"], **_FUZZ)
@given(text=mutated_text(_PAIR, expressions=False, specials=_pair_specials()))
def test_fuzz_pair_files(text, tmp_path_factory):
    _pair_case(text, tmp_path_factory)


# a mutated file may name any length unit: loading it warns, as documented
@pytest.mark.filterwarnings("ignore::cspace.io.UnitWarning")
@settings(max_examples=CASES["model"], **_FUZZ)
@given(text=mutated_text(_MODEL, expressions=True, specials=_model_specials()),
       defect=st.booleans())
def test_fuzz_model_files(text, defect, tmp_path_factory):
    _model_case(text, defect, tmp_path_factory)


# a mutated file may name any length unit: loading it warns, as documented
@pytest.mark.filterwarnings("ignore::cspace.io.UnitWarning")
@pytest.mark.slow
@settings(max_examples=CASES["pair"] * SLOW_FACTOR, **_FUZZ)
@given(text=mutated_text(_PAIR, expressions=False, specials=_pair_specials()))
def test_fuzz_pair_files_slow(text, tmp_path_factory):
    _pair_case(text, tmp_path_factory)


# a mutated file may name any length unit: loading it warns, as documented
@pytest.mark.filterwarnings("ignore::cspace.io.UnitWarning")
@pytest.mark.slow
@settings(max_examples=CASES["model"] * SLOW_FACTOR, **_FUZZ)
@given(text=mutated_text(_MODEL, expressions=True, specials=_model_specials()),
       defect=st.booleans())
def test_fuzz_model_files_slow(text, defect, tmp_path_factory):
    _model_case(text, defect, tmp_path_factory)


# ---------------------------------------------------------------- DXF drawings

def _base_dxf() -> list:
    pytest.importorskip("ezdxf")
    from mechanisms.dxf import export_dxf
    from mechanisms.userfile import load_model
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "cam.dxf"
        export_dxf(load_model(EXAMPLE).build(), p)
        return p.read_text().splitlines()


_DXF_PARTS = [{"layer": "cam", "name": "cam", "axis": {"type": "rotation", "center": [0, 0]}},
              {"layer": "follower", "name": "follower",
               "axis": {"type": "translation", "direction": [0, 1], "origin": [0, 21]}}]
DXF_VALUES = ["nan", "inf", "-inf", "1e309", "-1e308", "1e-320", "0", "-0", "", "abc",
              "9" * 5000, "1e15", "0.0000001", "cam", "follower", "FOOBAR", "8", "0",
              "ENTITIES", "EOF", "\x00"]


@st.composite
def mutated_dxf(draw, lines):
    lines = list(lines)
    start = lines.index("ENTITIES")
    stop = len(lines) - 1 - lines[::-1].index("ENDSEC")
    for _ in range(draw(st.integers(1, 3))):
        stop = min(stop, len(lines))
        if stop <= start + 2:
            break
        i = draw(st.integers(start + 1, stop - 1))
        kind = draw(st.sampled_from(["value", "value", "number", "delete", "dup", "insert",
                                     "truncate"]))
        if kind == "value":
            lines[i | 1 if (i - start) % 2 == 0 else i] = draw(st.sampled_from(DXF_VALUES))
        elif kind == "number":
            try:
                v = float(lines[i])
                lines[i] = repr(v * draw(st.sampled_from([1 + 1e-9, 1e6, 1e-6, -1.0, 0.0])))
            except ValueError:
                pass
        elif kind == "delete":
            j = i - ((i - start - 1) % 2)
            del lines[j:j + 2 * draw(st.integers(1, 4))]
        elif kind == "dup":
            j = i - ((i - start - 1) % 2)
            k = 2 * draw(st.integers(1, 12))
            lines[j:j] = lines[j:j + k]
        elif kind == "insert":
            j = i - ((i - start - 1) % 2)
            lines[j:j] = ["  0", draw(st.sampled_from(["FOOBAR", "LINE", "ARC", "CIRCLE",
                                                       "LWPOLYLINE", "TEXT"]))]
        else:
            lines = lines[:i]
    return "\n".join(lines) + "\n"


def _load_dxf(p):
    from mechanisms.dxf import import_dxf
    return import_dxf(p, parts=_DXF_PARTS, units="mm")


try:
    _DXF = _base_dxf()
except BaseException:    # ezdxf missing: the DXF tests skip
    _DXF = None


@pytest.mark.skipif(_DXF is None, reason="needs the dxf extra")
@settings(max_examples=CASES["dxf"], **_FUZZ)
@given(text=mutated_dxf(_DXF or ["ENTITIES", "ENDSEC"]))
def test_fuzz_dxf_drawings(text, tmp_path_factory):
    _run("dxf", _load_dxf, text, _TMP)


@pytest.mark.slow
@pytest.mark.skipif(_DXF is None, reason="needs the dxf extra")
@settings(max_examples=CASES["dxf"] * SLOW_FACTOR, **_FUZZ)
@given(text=mutated_dxf(_DXF or ["ENTITIES", "ENDSEC"]))
def test_fuzz_dxf_drawings_slow(text, tmp_path_factory):
    _run("dxf", _load_dxf, text, _TMP)


def test_fuzz_bases_are_clean(tmp_path):
    """The unmutated documents load and analyse cleanly (so that mutations, not
    the bases, make the errors)."""
    _run("pair", _load_pair, json.dumps(_PAIR), tmp_path)
    _run("model", _load_model, json.dumps(_MODEL), tmp_path, defect=True)
    if _DXF is not None:
        _run("dxf", _load_dxf, "\n".join(_DXF) + "\n", tmp_path)
    assert {k for k in OUTCOMES if k.endswith("clean")} >= {"pair clean", "model clean"}
