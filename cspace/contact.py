"""Contact curves between the features of two fixed-axis parts.

For every feature pair that can touch (:mod:`cspace.pruning`) and each of its
contact equations (:mod:`cspace.equations`: point-line or point-circle, solved
in closed form for q2 as a function of q1), the curve is the set of
configurations where the contact is real: the contact point inside both
features and the vertex's material cone on the free side of the other feature.
Curves are trimmed there, with end points found by root finding to
``Accuracy.root_tol`` (:mod:`cspace.roots`), and drawn as adaptive polylines.

A follower feature concentric with the follower's rotation centre (or a line
parallel to the slide) gives a contact that does not depend on q2: a *vertical*
curve ``q1 = const`` (:class:`VerticalCurve`).

``Feature``, ``features``, ``Equation`` and ``feature_pairs`` are re-exported
here from :mod:`cspace.features`, :mod:`cspace.equations` and
:mod:`cspace.pruning`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .accuracy import Accuracy
from .equations import Equation, Kernel
from .features import Feature, features
from .geom2d import TWO_PI, degrees_hint
from .geometry import Pair, Rotation
from .metric import coord_scale
from .pruning import feature_pairs
from .roots import adaptive_polyline, refine_root, vroots
from .tolerances import ROUNDING

__all__ = ["Equation", "Feature", "features", "ContactCurve", "VerticalCurve", "contact_curves",
           "CurveSet", "feature_pairs"]


# --------------------------------------------------------------------------- features



































# --------------------------------------------------------------------------- kernels















# --------------------------------------------------------------------------- curves

def _label(fa: Feature, fb: Feature, pair: Pair) -> str:
    return f"{pair.driver.name}:{fa.name}|{pair.follower.name}:{fb.name}"


@dataclass(frozen=True, eq=False)
class ContactCurve:
    """One trimmed branch of a contact curve: q2 = f(q1) on [q1_start, q1_end].

    Attributes
    ----------
    label : str
        ``"driver:feature|follower:feature"``.
    kind : str
        Feature kinds, e.g. ``"arc-line"``; ``"arc-arc-int"`` for internal arc contact.
    branch : int
        +1 / -1 (two-branch equations), 0 (point-line with a sliding follower).
    features : tuple
        Feature keys ``((0, loop, seg, kind), (1, loop, seg, kind))``.
    depends : frozenset of str
        Model parameters the contact equation depends on (empty without a model).
    q1_start, q1_end : float
        The trimmed driver range (rad or length).
    """

    label: str
    kind: str
    branch: int
    features: tuple
    depends: frozenset
    q1_start: float
    q1_end: float
    kernel: Kernel = field(repr=False)
    periodic: bool = field(default=True, repr=False)
    q2_origin: float = field(default=0.0, repr=False)
    start_closed: bool = field(default=True, repr=False)
    end_closed: bool = field(default=True, repr=False)

    @property
    def bi(self) -> int:
        return 0 if self.branch >= 0 else 1

    @property
    def key(self) -> tuple:
        """Identity of the curve independent of trimming: features + branch."""
        return (self.features, self.branch)

    def evaluate(self, q1):
        """Exact q2 at driver coordinates ``q1`` (array), wrapped into the follower
        window for a rotating follower."""
        q2 = self.kernel.solve(q1)[0][self.bi]
        if self.periodic:
            q2 = (q2 - self.q2_origin) % TWO_PI + self.q2_origin
        return q2

    def raw(self, q1):
        """q2 without wrapping (continuous along the curve)."""
        return self.kernel.solve(q1)[0][self.bi]

    def values(self, q1):
        """``(evaluate(q1), raw(q1))`` from one solve."""
        r = self.kernel.solve(q1)[0][self.bi]
        if self.periodic and r.shape == (1,):
            v = float(r[0])  # Python's float % is numpy's remainder, bit for bit
            return np.array([(v - self.q2_origin) % TWO_PI + self.q2_origin]), r
        if self.periodic:
            return (r - self.q2_origin) % TWO_PI + self.q2_origin, r
        return r, r

    def margin(self, q1):
        """Validity margin along the branch (>= 0 where a real contact)."""
        return self.kernel.margin(q1, self.bi)[0]

    def polyline(self, accuracy: Accuracy | None = None) -> np.ndarray:
        """Adaptive polyline (n, 2) in (q1, q2) whose chord error is at most
        ``accuracy.chord`` in the C-space metric.  q2 is continuous (unwrapped)."""
        from .accuracy import as_accuracy
        acc = as_accuracy(accuracy)
        s2 = 1.0 if self.periodic else 1.0 / self.kernel.scale
        s1 = coord_scale(self.kernel.axis_a, self.kernel.scale)
        return adaptive_polyline(self.raw, self.q1_start, self.q1_end, acc.chord,
                                 acc.max_step * s1, scale=s2, scale1=1.0 / s1)

    def point_world(self, q1):
        """(contact configuration) helper: (q1, q2) arrays."""
        q1 = np.atleast_1d(np.asarray(q1, dtype=float))
        return np.stack([q1, self.evaluate(q1)], -1)


@dataclass(frozen=True, eq=False)
class VerticalCurve:
    """A contact independent of q2: the segment q1 = ``q1_value``, q2 in [q2_lo, q2_hi]."""

    label: str
    kind: str
    features: tuple
    depends: frozenset
    q1_value: float
    q2_lo: float
    q2_hi: float
    kernel: Kernel = field(repr=False)
    branch: int = 0

    @property
    def key(self) -> tuple:
        return (self.features, "vertical")








def _valid_runs(grid, mvals):
    """Maximal runs of grid indices where the margin is >= 0: list of (i, j) and
    the root brackets (grid index pairs) of their interior ends, lower and upper."""
    ok = mvals >= 0
    n = len(grid)
    if not ok.any():
        return [], [], []
    d = np.diff(ok.astype(int))
    starts = list(np.nonzero(d == 1)[0] + 1)
    stops = list(np.nonzero(d == -1)[0])
    if ok[0]:
        starts = [0] + starts
    if ok[-1]:
        stops = stops + [n - 1]
    lo_br = [(i - 1, i) for i in starts if i > 0]
    hi_br = [(j, j + 1) for j in stops if j < n - 1]
    return list(zip(starts, stops)), lo_br, hi_br


def _branch_intervals(mfun, grid, mvals, tol) -> list:
    """Per branch, the maximal grid intervals where the margin is >= 0, with the
    interior ends refined in one vectorised root search over every branch.

    ``mfun(x)`` gives the margins of all B branches at x, shape (B, len(x));
    ``mvals`` is ``mfun(grid)``.  Returns B lists of (lo, hi, at_grid_start,
    at_grid_end)."""
    n = len(grid)
    runs, lo_br, hi_br, own_lo, own_hi = [], [], [], [], []
    for bi, mv in enumerate(mvals):
        r, lb, hb = _valid_runs(grid, mv)
        runs.append(r)
        lo_br += lb
        hi_br += hb
        own_lo += [bi] * len(lb)
        own_hi += [bi] * len(hb)
    br = np.array(lo_br + hi_br, dtype=int).reshape(-1, 2)
    owner = np.array(own_lo + own_hi, dtype=int)

    roots = vroots(_rows(mfun, owner), grid[br[:, 0]], grid[br[:, 1]], tol,
                   fa=mvals[owner, br[:, 0]], fb=mvals[owner, br[:, 1]])
    roots = _plateau_edges(mfun, roots, owner, grid[br[:, 0]], grid[br[:, 1]],
                           len(lo_br), tol)
    n_lo = len(lo_br)
    out = []
    for bi, r in enumerate(runs):
        lo_r = iter(roots[:n_lo][owner[:n_lo] == bi])
        hi_r = iter(roots[n_lo:][owner[n_lo:] == bi])
        iv = []
        for i, j in r:
            lo = grid[i] if i == 0 else float(next(lo_r))
            hi = grid[j] if j == n - 1 else float(next(hi_r))
            iv.append((lo, hi, i == 0, j == n - 1))
        out.append(iv)
    for bi, lo, hi in _short_runs(mfun, grid, mvals, tol):
        out[bi] = sorted(out[bi] + [(lo, hi, False, False)])
    return out


def _rows(mfun, owner):
    """The margin of search k's own branch at its abscissa, as :func:`vroots`
    asks: ``x`` holds one abscissa per search, repeated in blocks, and search k
    belongs to branch ``owner[k]`` of ``mfun`` (shape (B, len(x)))."""
    owner = np.asarray(owner, dtype=int)

    def f(x):
        reps = len(x) // max(len(owner), 1)
        return mfun(x)[np.tile(owner, reps), np.arange(len(x))]
    return f


def _valid_sign(m):
    """Margins with exact zeros made positive (valid), for a sign search."""
    return np.where(m == 0, np.finfo(float).tiny, m)


def _plateau_edges(mfun, roots, owner, a, b, n_lo: int, tol: float):
    """Valid-run ends where the margin is exactly 0 over a stretch.

    The root search stops where the margin is exactly 0.  Where one condition
    is 0 all along (a vertex whose edge lies along the line it touches), that
    is anywhere on the valid stretch, not at its edge.  A root with margin 0
    whose neighbour ``tol`` towards the invalid end is valid too is searched
    again for the edge of {margin >= 0} (zeros counted as valid).  Elsewhere
    the roots are returned unchanged."""
    if not roots.size:
        return roots
    rows = np.arange(roots.size)
    m0 = mfun(roots)[owner, rows]
    sus = np.nonzero(m0 == 0)[0]
    if not sus.size:
        return roots
    # invalid side: left of a run's lower end (brackets < n_lo), right of its upper
    step = np.where(sus < n_lo, -tol, tol)
    probe = np.clip(roots[sus] + step, np.minimum(a[sus], b[sus]), np.maximum(a[sus], b[sus]))
    flat = sus[mfun(probe)[owner[sus], np.arange(sus.size)] >= 0]
    if not flat.size:
        return roots
    rows_flat = _rows(mfun, owner[flat])
    inv = np.where(flat < n_lo, a[flat], b[flat])
    out = roots.copy()
    out[flat] = vroots(lambda xx: _valid_sign(rows_flat(xx)), inv, roots[flat], tol)
    return out


#: Interior samples per step of the search for short valid runs (_short_runs).
_ZOOM = 8


def _short_runs(mfun, grid, mvals, tol, max_levels: int = 40) -> list:
    """Valid runs that lie wholly between two grid points: (branch, lo, hi).

    A contact shorter than the scan step (a short chamfer, one edge of a
    finely polygonised profile) has a negative margin at both grid points
    around it.  Where the margin at both ends of a step is within reach of 0
    (at most half a step times twice the steepest slope the scan saw there),
    the step is searched: ``_ZOOM`` interior samples, then the same around the
    best of them, until a sample is valid (the run's ends are then refined to
    ``tol``), the best can no longer reach 0, or the step is shorter than
    ``tol``.  Steps that cannot hold a positive margin cost nothing more.
    """
    B, n = mvals.shape
    if n < 2:
        return []
    h = np.diff(grid)
    with np.errstate(invalid="ignore"):
        fin = np.isfinite(mvals)
        m = np.where(fin, mvals, -np.inf)
        slope = np.abs(np.diff(m, axis=1)) / h
        slope = np.where(np.isfinite(slope), slope, 0.0)
        steep = slope.copy()
        steep[:, 1:] = np.maximum(steep[:, 1:], slope[:, :-1])
        steep[:, :-1] = np.maximum(steep[:, :-1], slope[:, 1:])
        reach = np.maximum(2.0 * steep, 1.0) * h
        hi_end = np.maximum(m[:, :-1], m[:, 1:])
        cand = (m[:, :-1] < 0) & (m[:, 1:] < 0) & (hi_end > -0.5 * reach)
    bi, ki = np.nonzero(cand)
    if not bi.size:
        return []
    a = grid[ki].astype(float)
    b = grid[ki + 1].astype(float)
    a0, b0 = a.copy(), b.copy()
    c = (reach / h)[bi, ki]
    t = np.arange(1, _ZOOM + 1) / (_ZOOM + 1)
    found = np.full(bi.size, np.nan)
    live = np.ones(bi.size, dtype=bool)
    for _ in range(max_levels):
        idx = np.nonzero(live)[0]
        if not idx.size:
            break
        xs = a[idx, None] + (b - a)[idx, None] * t[None, :]
        vals = mfun(xs.ravel())[np.repeat(bi[idx], _ZOOM), np.arange(xs.size)]
        vals = np.where(np.isfinite(vals), vals, -np.inf).reshape(xs.shape)
        best = np.argmax(vals, axis=1)
        bv = vals[np.arange(idx.size), best]
        hit = bv >= 0
        found[idx[hit]] = xs[np.arange(idx.size), best][hit]
        live[idx[hit]] = False
        rest = ~hit
        r_idx = idx[rest]
        bb = best[rest]
        xr = xs[rest]
        na = np.where(bb > 0, xr[np.arange(r_idx.size), np.maximum(bb - 1, 0)], a[r_idx])
        nb = np.where(bb < _ZOOM - 1, xr[np.arange(r_idx.size), np.minimum(bb + 1, _ZOOM - 1)],
                      b[r_idx])
        a[r_idx], b[r_idx] = na, nb
        keep = (bv[rest] > -0.5 * c[r_idx] * (nb - na)) & (nb - na > tol)
        live[r_idx[~keep]] = False
    ok = np.nonzero(np.isfinite(found))[0]
    if not ok.size:
        return []
    x = found[ok]
    own = bi[ok]
    branch_margin = _rows(mfun, own)
    lo = vroots(branch_margin, a0[ok], x, tol)
    hi = vroots(branch_margin, x, b0[ok], tol)
    return [(int(o), float(l_), float(h_)) for o, l_, h_ in zip(own, lo, hi)]


def _valid_intervals(mfun, grid, mvals, tol):
    """Maximal intervals of the grid where the margin is >= 0, ends refined."""
    return _branch_intervals(lambda x: mfun(x)[None], grid, np.asarray(mvals)[None], tol)[0]


@dataclass(frozen=True)
class CurveSet:
    """All trimmed contact curves of a pair in a driver window.

    Attributes
    ----------
    curves : tuple of ContactCurve
    vertical : tuple of VerticalCurve
    n_candidates : int
        Feature pairs of compatible type.
    n_pruned : int
        Pairs removed by the broad phase.
    window : (float, float, float, float)
        (q1_lo, q1_hi, q2_lo, q2_hi).
    n_reused : int
        Feature pairs whose pieces came from a :class:`~cspace.cache.CurveCache`.
    """

    curves: tuple
    vertical: tuple
    n_candidates: int
    n_pruned: int
    window: tuple
    n_reused: int = 0


def _dep_of(feature: Feature, part_axis_key, deps) -> frozenset:
    if deps is None:
        return frozenset()
    s = set(deps.get(part_axis_key, ()))
    for k in feature.segs:
        s |= set(deps.get(k, ()))
    return frozenset(s)


def curve_pieces(pair: Pair, fa: Feature, fb: Feature, eq: str, owner: int, r: float,
                 window, accuracy: Accuracy, deps=None, periodic_q1: bool = True):
    """Trimmed curve pieces (and vertical pieces) of one feature pair."""
    L = pair.char_length
    k = Kernel(eq, owner, float(r), fa, fb, pair.driver.axis, pair.follower.axis, L)
    q1lo, q1hi, q2lo, q2hi = window
    kind = f"{fa.kind}-{fb.kind}"
    if fa.kind == "arc" and fb.kind == "arc":
        kind += "-ext" if fa.convex and fb.convex else "-int"
    label = _label(fa, fb, pair)
    feats = (fa.key + (fa.kind,), fb.key + (fb.kind,))
    dep = _dep_of(fa, (0, "axis"), deps) | _dep_of(fb, (1, "axis"), deps)
    periodic_q2 = isinstance(pair.follower.axis, Rotation)
    if k.is_vertical():
        return [], _vertical_pieces(k, label, kind, feats, dep, window, accuracy)
    s1 = coord_scale(pair.driver.axis, L)
    step = min(accuracy.scan_step * s1, (q1hi - q1lo) / 8)
    n = max(9, int(math.ceil((q1hi - q1lo) / step)) + 1)
    grid = np.linspace(q1lo, q1hi, n)

    def margins(x):
        m, q2 = k.margins(x)
        if not periodic_q2:
            m = np.minimum(m, np.minimum(q2 - q2lo, q2hi - q2) / L)
        return m

    # the ends of every branch's valid runs are refined in one vectorised search
    out = []
    for bi, intervals in enumerate(_branch_intervals(margins, grid, margins(grid),
                                                     accuracy.root_tol * s1)):
        branch = (1 if bi == 0 else -1) if k.nbranch == 2 else 0
        for lo, hi, at_lo, at_hi in intervals:
            if hi - lo <= accuracy.root_tol * 10 * s1:
                continue
            out.append(ContactCurve(label, kind, branch, feats, dep, float(lo), float(hi), k,
                                    periodic_q2, q2lo,
                                    start_closed=not (at_lo and periodic_q1),
                                    end_closed=not (at_hi and periodic_q1)))
    return out, []


def _vertical_pieces(k: Kernel, label, kind, feats, dep, window, accuracy):
    q1lo, q1hi, q2lo, q2hi = window
    s1, s2 = coord_scale(k.axis_a, k.scale), coord_scale(k.axis_b, k.scale)
    n = max(9, int(math.ceil((q1hi - q1lo) / (accuracy.scan_step * s1))) + 1)
    grid = np.linspace(q1lo, q1hi, n)
    res = k.vertical_residual(grid)
    roots = []
    for i in range(n - 1):
        if res[i] == 0:
            roots.append(grid[i])
        elif res[i] * res[i + 1] < 0:
            roots.append(refine_root(k.vertical_residual, grid[i], grid[i + 1], None,
                                       accuracy.root_tol * s1))
    roots = sorted(roots + _dipped_roots(k.vertical_residual, grid, res,
                                          accuracy.root_tol * s1))
    out = []
    m = max(17, int(math.ceil((q2hi - q2lo) / (accuracy.scan_step * s2))) + 1)
    q2g = np.linspace(q2lo, q2hi, m)
    for r in roots:
        mv = k.conditions(np.full(m, r), q2g)
        fn = lambda y, r=r: k.conditions(np.full(np.shape(y), r), y)
        for lo, hi, _, _ in _valid_intervals(fn, q2g, mv, accuracy.root_tol * s2):
            if hi - lo > accuracy.root_tol * 10 * s2:
                out.append(VerticalCurve(label, kind, feats, dep, float(r), float(lo), float(hi), k))
    return out


def _dipped_roots(fn, grid, res, tol) -> list:
    """The roots of ``fn`` that come in pairs between samples ``grid`` of it
    (``res``) with no sign change among them: at each sample that is a local
    extreme of a residual of one sign (a minimum of a positive one, a
    maximum of a negative one), the extreme of ``fn`` between the neighbouring
    samples, found to ``tol``; where it crosses zero, the root on either side
    of it.

    A contact that does not depend on the follower's position exists where
    its residual of q1 crosses zero, and a shallow one crosses it twice
    within less than a scan step: a crank pin rising 0.0002 mm above a
    slot's end (parallel to the slide) crossed it 0.009 rad apart, between
    two samples 0.005 rad apart at `fast`, and the jam went unseen."""
    from scipy.optimize import minimize_scalar
    n = len(grid)
    out = []
    for i in range(n):
        r = res[i]
        if r == 0 or not math.isfinite(r):
            continue
        sg = 1.0 if r > 0 else -1.0
        lo, hi = max(i - 1, 0), min(i + 1, n - 1)
        if sg * res[lo] < sg * r or sg * res[hi] < sg * r:
            continue                    # not a local extreme of its sign
        if lo < i and res[lo] * r <= 0 or hi > i and res[hi] * r <= 0:
            continue                    # a sign change next to it: found above
        if abs(r) > max(abs(res[lo] - r), abs(res[hi] - r)):
            # a smooth residual dips below its nearest sample by less than
            # an eighth of the larger difference to the neighbours
            continue
        a, b = float(grid[lo]), float(grid[hi])
        got = minimize_scalar(lambda x: sg * float(fn(np.array([x]))[0]), bounds=(a, b),
                              method="bounded", options={"xatol": tol})
        x = float(got.x)
        if not got.fun < 0.0:
            continue
        for u, v in ((a, x), (x, b)):
            if float(fn(np.array([u]))[0]) * float(fn(np.array([v]))[0]) < 0:
                out.append(refine_root(fn, u, v, None, tol))
    return out


def default_window(pair: Pair) -> tuple:
    """One period of each rotating coordinate; for a sliding coordinate, the range
    over which the parts can touch (from the broad-phase bounds) plus 5 % margin."""
    out = []
    for role in (0, 1):
        part = pair.parts[role]
        if isinstance(part.axis, Rotation):
            out += [0.0, TWO_PI]
            continue
        other = pair.parts[1 - role]
        e = np.array(part.axis.direction)
        # slide range: the part's projection interval must overlap the other part's
        # reach along e
        x0, y0, x1, y1 = part.bounds()
        corners = np.array([[x0, y0], [x1, y0], [x0, y1], [x1, y1]])
        proj = corners @ e
        if isinstance(other.axis, Rotation):
            c = float(np.array(other.axis.center) @ e)
            R = other.reach()
            lo, hi = c - R, c + R
        else:
            ox0, oy0, ox1, oy1 = other.bounds()
            oc = np.array([[ox0, oy0], [ox1, oy0], [ox0, oy1], [ox1, oy1]]) @ e
            lo, hi = oc.min(), oc.max()
        smin = lo - proj.max()
        smax = hi - proj.min()
        pad = 0.05 * (smax - smin)
        out += [float(smin - pad), float(smax + pad)]
    return tuple(out)


def contact_curves(pair: Pair, accuracy: Accuracy | str | None = None, *, window=None,
                   deps=None, prune: bool = True, cache=None) -> CurveSet:
    """All trimmed contact curves of a pair.

    Parameters
    ----------
    pair : Pair
    accuracy : Accuracy, preset name or None
    window : (q1_lo, q1_hi, q2_lo, q2_hi), optional
        C-space window; defaults to :func:`default_window`.  Only the q1 range asked
        for is computed.
    deps : mapping, optional
        Parameter dependencies: ``{(part, loop, seg): names, (part, "axis"): names}``
        (see :meth:`mechanisms.models.Model.dependencies`).
    prune : bool
        Apply the broad phase (off only for benchmarks).
    cache : cspace.cache.CurveCache, optional
        Reuse the pieces of feature pairs whose geometry, axes and settings are
        unchanged (bit for bit) since they were cached.
    """
    from .accuracy import as_accuracy
    acc = as_accuracy(accuracy)
    win = _check_window(pair, window)
    if prune:
        cands, pruned = feature_pairs(pair)
    else:
        cands, pruned = feature_pairs(pair, margin_rel=math.inf)[0], 0
    periodic_q1 = isinstance(pair.driver.axis, Rotation) and is_period(win[0], win[1])
    curves, vert = [], []
    reused = 0
    if cache is not None:
        L = pair.char_length
        ax = (pair.driver.axis, pair.follower.axis, pair.driver.name, pair.follower.name)
    for fa, fb, eq, owner, r in cands:
        if cache is None:
            c, v = curve_pieces(pair, fa, fb, eq, owner, r, win, acc, deps, periodic_q1)
        else:
            dep = _dep_of(fa, (0, "axis"), deps) | _dep_of(fb, (1, "axis"), deps)
            key = (fa, fb, eq, owner, float(r), ax, L, win, acc, periodic_q1, dep)
            h0 = cache.hits
            c, v = cache.get_or_compute(key, lambda fa=fa, fb=fb, eq=eq, owner=owner, r=r:
                                        curve_pieces(pair, fa, fb, eq, owner, r, win, acc,
                                                     deps, periodic_q1))
            reused += cache.hits - h0
        curves += c
        vert += v
    return CurveSet(tuple(curves), tuple(vert), len(cands) + pruned, pruned, win, reused)


#: Narrowest window (C-space metric: rad, or slide / characteristic length).
MIN_WINDOW = 1e-6
#: Widest window of a sliding coordinate, in characteristic lengths.
MAX_SLIDE_WINDOW = 1e4


def _period_tol(lo: float, hi: float) -> float:
    """Rounding allowed when ``hi - lo`` is compared with 2 pi (it grows with
    the window's distance from 0)."""
    return ROUNDING + 8 * np.finfo(float).eps * max(abs(lo), abs(hi))


def is_period(lo: float, hi: float) -> bool:
    """Whether the window [lo, hi] of a rotating coordinate is one full turn."""
    return abs(hi - lo - TWO_PI) <= _period_tol(lo, hi)


def _check_window(pair: Pair, window):
    from .argcheck import getvector
    from .errors import InputError
    if window is None:
        return default_window(pair)
    w = getvector(window, 4, "window")
    if not (w[1] > w[0] and w[3] > w[2]):
        raise InputError(f"window must be (q1_lo, q1_hi, q2_lo, q2_hi) with lo < hi, got "
                         f"{tuple(w.tolist())}", name="window", value=window)
    L = pair.char_length
    for i, part in enumerate(pair.parts):
        rot = isinstance(part.axis, Rotation)
        span = (w[2 * i + 1] - w[2 * i]) / (1.0 if rot else L)
        if span < MIN_WINDOW:
            unit = "rad" if rot else f"{pair.units or 'length units'} ({span:.3g} of the " \
                                     f"characteristic length {L:.6g})"
            raise InputError(f"window for q{i + 1} spans {w[2 * i + 1] - w[2 * i]:.3g} {unit}; "
                             f"at least {MIN_WINDOW:g} rad (or {MIN_WINDOW:g} of the "
                             f"characteristic length for a slide) is allowed", name="window",
                             value=window)
        if not rot and span > MAX_SLIDE_WINDOW:
            raise InputError(f"window for q{i + 1} spans {w[2 * i + 1] - w[2 * i]:.3g} "
                             f"{pair.units or 'length units'}, {span:.3g} characteristic "
                             f"lengths ({L:.6g}); at most {MAX_SLIDE_WINDOW:g} are allowed "
                             f"(the parts touch only within a few)", name="window",
                             value=window)
        if rot and w[2 * i + 1] - w[2 * i] > TWO_PI + _period_tol(w[2 * i], w[2 * i + 1]):
            lo_, hi_ = float(w[2 * i]), float(w[2 * i + 1])
            over = hi_ - lo_ - TWO_PI
            rule = (f"at most one period is allowed (2 pi = {TWO_PI!r}, to "
                    f"{_period_tol(lo_, hi_):.1g} rad; this one {hi_ - lo_:.10g}, {over:.3g} rad "
                    f"more): give q{i + 1}_hi = q{i + 1}_lo + {TWO_PI!r} for a whole turn"
                    if over < 1e-3 else "at most one period (2 pi) is allowed")
            raise InputError(f"window for rotating coordinate q{i + 1} spans "
                             f"{hi_ - lo_:.6g} rad; {rule}{degrees_hint(lo_, hi_)}",
                             name="window", value=window)
    if isinstance(pair.follower.axis, Rotation) and not is_period(w[2], w[3]):
        lo_, hi_ = float(w[2]), float(w[3])
        raise InputError(f"the follower window of a rotating follower must be one full period "
                         f"(2 pi), {TWO_PI!r} rad to {_period_tol(lo_, hi_):.1g} rad; got q2 "
                         f"from {lo_:.10g} to {hi_:.10g}, a span of {hi_ - lo_:.10g} "
                         f"({hi_ - lo_ - TWO_PI:+.3g} rad off): give q2_hi = q2_lo + "
                         f"{TWO_PI!r} (q2_lo + 2 pi), or leave the window out (its default "
                         f"is a full period)", name="window", value=window)
    return tuple(float(x) for x in w)
