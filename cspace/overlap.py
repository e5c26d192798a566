"""Exact part-overlap and distance tests on the true line/arc geometry.

These work on arrays of configurations.  Two parts overlap at q when a boundary
segment of one crosses a boundary segment of the other, or when one part's loop
lies inside the other's material.  Nothing here approximates arcs by polygons.
"""

from __future__ import annotations

import math

import numpy as np

from .geom2d import line_circle_quadratic, line_line, radical_foot, wrap_pi
from .geometry import Line, Pair, Part, Rotation, place_points
from .tolerances import FULL_CIRCLE_SLACK, SLACK, TINY

__all__ = ["parts_overlap", "min_distance", "place_part", "local_point"]


def _q(q) -> np.ndarray:
    q = np.asarray(q, dtype=float)
    if q.ndim == 1 and q.shape[0] == 2:
        q = q[None, :]
    return q



def local_point(part: Part, q, pts):
    """Body coordinates (at q = 0) of world points ``pts`` (N, 2) when the part is at q (N,)."""
    axis = part.axis
    pts = np.asarray(pts, dtype=float)
    if isinstance(axis, Rotation):
        return place_points(axis, -np.asarray(q, dtype=float), pts)
    e = np.asarray(axis.direction)
    return np.stack([pts[..., 0] - q * e[0], pts[..., 1] - q * e[1]], -1)


def place_part(part: Part, q):
    """World segments of a part at coordinates q (N,): list of dicts of arrays."""
    q = np.asarray(q, dtype=float)
    ang = q if isinstance(part.axis, Rotation) else np.zeros_like(q)
    out = []
    for lp in part.loops:
        for s in lp.segments:
            if isinstance(s, Line):
                out.append(("line", place_points(part.axis, q, s.start), place_points(part.axis, q, s.end)))
            else:
                out.append(("arc", place_points(part.axis, q, s.center), s.radius,
                            s.mid_angle + ang, 0.5 * s.sweep))
    return out


def _seg_radial(part: Part) -> np.ndarray:
    """(S, 2): range of distances of each segment's points from the part's
    rotation centre (conservative for arcs: their whole circle)."""
    c = np.asarray(part.axis.center, dtype=float)
    out = []
    for lp in part.loops:
        for sg in lp.segments:
            if isinstance(sg, Line):
                a, b = np.asarray(sg.start, float), np.asarray(sg.end, float)
                ab = b - a
                t = np.clip(np.dot(c - a, ab) / max(np.dot(ab, ab), TINY), 0.0, 1.0)
                out.append((np.hypot(*(a + t * ab - c)),
                            max(np.hypot(*(a - c)), np.hypot(*(b - c)))))
            else:
                dc = np.hypot(*(np.asarray(sg.center, float) - c))
                out.append((max(dc - sg.radius, 0.0), dc + sg.radius))
    return np.array(out, dtype=float).reshape(-1, 2)


def _annulus_candidates(pair: Pair):
    """(driver segment index, follower segment indices) that may meet at any
    configuration: for two rotating parts, segments whose swept annuli meet
    (found through the follower's sorted outer radii); otherwise all pairs."""
    na = sum(len(lp.segments) for lp in pair.driver.loops)
    nb = sum(len(lp.segments) for lp in pair.follower.loops)
    if not (isinstance(pair.driver.axis, Rotation) and isinstance(pair.follower.axis, Rotation)):
        allb = np.arange(nb)
        return [(i, allb) for i in range(na)]
    ra, rb = _seg_radial(pair.driver), _seg_radial(pair.follower)
    D = float(np.hypot(*np.subtract(pair.driver.axis.center, pair.follower.axis.center)))
    grow = SLACK * (D + float(ra[:, 1].max()) + float(rb[:, 1].max()))
    order = np.argsort(rb[:, 1], kind="stable")
    bmax = rb[order, 1]
    out = []
    for i, (amin, amax) in enumerate(ra):
        cand = order[np.searchsorted(bmax, D - amax - grow, side="left"):]
        ok = (amin - rb[cand, 1] <= D + grow) & (rb[cand, 0] - amax <= D + grow)
        out.append((i, np.sort(cand[ok])))
    return out


def _boxes(segs) -> np.ndarray:
    """Bounding boxes (S, N, 4: xmin, ymin, xmax, ymax) of placed segments,
    grown by a rounding margin; an arc's is its whole circle's."""
    out = []
    for sg in segs:
        if sg[0] == "line":
            lo, hi = np.minimum(sg[1], sg[2]), np.maximum(sg[1], sg[2])
        else:
            lo, hi = sg[1] - sg[2], sg[1] + sg[2]
        grow = SLACK * (np.abs(lo) + np.abs(hi) + (hi - lo))
        out.append(np.concatenate([lo - grow, hi + grow], -1))
    return np.array(out).reshape(len(segs), -1, 4)


def _on_arc(ang, mid, half):
    if half >= math.pi - FULL_CIRCLE_SLACK:
        return np.ones(np.shape(ang), dtype=bool)
    return np.abs(wrap_pi(ang - mid)) <= half


def _x_line_line(a, b):
    t, u, rxs = line_line(a[1], a[2] - a[1], b[1], b[2] - b[1])
    return (rxs != 0) & (t >= 0) & (t <= 1) & (u >= 0) & (u <= 1)


def _x_line_arc(a, b):
    p = a[1]
    d = a[2] - a[1]
    c, r, mid, half = b[1], b[2], b[3], b[4]
    A, B, disc = line_circle_quadratic(p, d, c, r)
    sq = np.sqrt(np.where(disc > 0, disc, 0.0))
    hit = np.zeros(disc.shape, dtype=bool)
    for sgn in (-1.0, 1.0):
        t = (-B + sgn * sq) / (2 * A)
        x = p + t[..., None] * d
        ang = np.arctan2(x[..., 1] - c[..., 1], x[..., 0] - c[..., 0])
        hit |= (disc > 0) & (t >= 0) & (t <= 1) & _on_arc(ang, mid, half)
    return hit


def _x_arc_arc(a, b):
    c1, r1, m1, h1 = a[1], a[2], a[3], a[4]
    c2, r2, m2, h2 = b[1], b[2], b[3], b[4]
    base, n, h2sq = radical_foot(c1, r1, c2, r2)
    h = np.sqrt(np.where(h2sq > 0, h2sq, 0.0))
    hit = np.zeros(h.shape, dtype=bool)
    for sgn in (-1.0, 1.0):
        x = base + sgn * h[..., None] * n
        a1 = np.arctan2(x[..., 1] - c1[..., 1], x[..., 0] - c1[..., 0])
        a2 = np.arctan2(x[..., 1] - c2[..., 1], x[..., 0] - c2[..., 0])
        hit |= (h2sq > 0) & _on_arc(a1, m1, h1) & _on_arc(a2, m2, h2)
    return hit


def _crosses(a, b):
    if a[0] == "line" and b[0] == "line":
        return _x_line_line(a, b)
    if a[0] == "line":
        return _x_line_arc(a, b)
    if b[0] == "line":
        return _x_line_arc(b, a)
    return _x_arc_arc(a, b)


def _inside(part: Part, pts) -> np.ndarray:
    """Even-odd ray test of body points (N, 2) against a part at q = 0."""
    x, y = pts[..., 0], pts[..., 1]
    cnt = np.zeros(x.shape, dtype=int)
    for lp in part.loops:
        for s in lp.segments:
            if isinstance(s, Line):
                (x0, y0), (x1, y1) = s.start, s.end
                cond = (y0 > y) != (y1 > y)
                dy = (y1 - y0) if y1 != y0 else 1.0
                xi = x0 + (y - y0) * (x1 - x0) / dy
                cnt += cond & (xi > x)
            else:
                cx, cy = s.center
                dy = y - cy
                inside = np.abs(dy) < s.radius
                dx = np.sqrt(np.where(inside, s.radius ** 2 - dy * dy, 0.0))
                for xi in (cx - dx, cx + dx):
                    ang = np.arctan2(dy, xi - cx)
                    cnt += inside & (xi > x) & _on_arc(ang, s.mid_angle, 0.5 * s.sweep)
    return cnt % 2 == 1


def parts_overlap(pair: Pair, q) -> np.ndarray:
    """Whether the parts' interiors overlap at configurations q.

    Parameters
    ----------
    q : (2,) or (N, 2) float
        Configurations (q1, q2).

    Returns
    -------
    (N,) bool
        Exact on the line/arc geometry.  Configurations exactly at contact may
        go either way; use :func:`min_distance` there.
    """
    q = _q(q)
    sa = place_part(pair.driver, q[:, 0])
    sb = place_part(pair.follower, q[:, 1])
    hit = np.zeros(q.shape[0], dtype=bool)
    # broad phase: only segments whose bounding boxes meet at some configuration
    # can cross (the exact test below is unchanged); keeps large drawings whose
    # parts mostly do not touch near-linear instead of n1 * n2 exact tests
    ba, bb = _boxes(sa), _boxes(sb)
    for i, cand in _annulus_candidates(pair):
        a = sa[i]
        meet = ((ba[i, None, :, 0] <= bb[cand, :, 2]) & (bb[cand, :, 0] <= ba[i, None, :, 2])
                & (ba[i, None, :, 1] <= bb[cand, :, 3]) & (bb[cand, :, 1] <= ba[i, None, :, 3]))
        for j in cand[meet.any(axis=1)]:
            hit |= _crosses(a, sb[j])
    # containment of whole loops
    rest = ~hit
    if rest.any():
        qa, qb = q[rest, 0], q[rest, 1]
        for lp in pair.driver.loops:
            p0 = lp.segments[0].start_point
            w = place_points(pair.driver.axis, qa, p0)
            hit[rest] |= _inside(pair.follower, local_point(pair.follower, qb, w))
        for lp in pair.follower.loops:
            p0 = lp.segments[0].start_point
            w = place_points(pair.follower.axis, qb, p0)
            hit[rest] |= _inside(pair.driver, local_point(pair.driver, qa, w))
    return hit


# ----------------------------------------------------------------------- distances

def _pt_line(p, a, b):
    ab = b - a
    t = np.clip(((p - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), TINY), 0, 1)
    x = a + t[..., None] * ab
    return np.hypot(*(p - x).T) if p.ndim == 1 else np.hypot((p - x)[..., 0], (p - x)[..., 1])


def _pt_arc(p, c, r, mid, half):
    v = p - c
    ang = np.arctan2(v[..., 1], v[..., 0])
    dc = np.hypot(v[..., 0], v[..., 1])
    on = _on_arc(ang, mid, half)
    e1 = c + r * np.stack([np.cos(mid - half), np.sin(mid - half)], -1)
    e2 = c + r * np.stack([np.cos(mid + half), np.sin(mid + half)], -1)
    d_end = np.minimum(np.hypot(*(p - e1).T) if p.ndim == 1 else np.hypot((p - e1)[..., 0], (p - e1)[..., 1]),
                       np.hypot(*(p - e2).T) if p.ndim == 1 else np.hypot((p - e2)[..., 0], (p - e2)[..., 1]))
    return np.where(on, np.abs(dc - r), d_end)


def _ends(s):
    if s[0] == "line":
        return [s[1], s[2]]
    c, r, mid, half = s[1], s[2], s[3], s[4]
    return [c + r * np.stack([np.cos(mid - half), np.sin(mid - half)], -1),
            c + r * np.stack([np.cos(mid + half), np.sin(mid + half)], -1)]


def _pt_seg(p, s):
    if s[0] == "line":
        return _pt_line(p, s[1], s[2])
    return _pt_arc(p, s[1], s[2], s[3], s[4])


def _seg_dist(a, b):
    d = np.full(np.shape(a[1])[:-1], np.inf)
    for p in _ends(a):
        d = np.minimum(d, _pt_seg(p, b))
    for p in _ends(b):
        d = np.minimum(d, _pt_seg(p, a))
    # interior-interior minima
    if a[0] == "arc" and b[0] == "arc":
        c1, r1, c2, r2 = a[1], a[2], b[1], b[2]
        dv = c2 - c1
        dd = np.hypot(dv[..., 0], dv[..., 1])
        u = dv / np.where(dd > 0, dd, 1.0)[..., None]
        # concentric arcs have no line of centres: their nearest points, |r1 - r2|
        # apart, include an end of one of them wherever their ranges overlap,
        # which the end distances above already hold
        apart = dd > 0
        for s1 in (-1, 1):
            for s2 in (-1, 1):
                p1 = c1 + s1 * r1 * u
                p2 = c2 + s2 * r2 * u
                a1 = np.arctan2(s1 * u[..., 1], s1 * u[..., 0])
                a2 = np.arctan2(s2 * u[..., 1], s2 * u[..., 0])
                ok = apart & _on_arc(a1, a[3], a[4]) & _on_arc(a2, b[3], b[4])
                dist = np.hypot((p1 - p2)[..., 0], (p1 - p2)[..., 1])
                d = np.where(ok, np.minimum(d, dist), d)
    elif a[0] == "arc" or b[0] == "arc":
        ln, ar = (a, b) if a[0] == "line" else (b, a)
        p0, p1 = ln[1], ln[2]
        dv = p1 - p0
        L = np.hypot(dv[..., 0], dv[..., 1])
        t_hat = dv / L[..., None]
        n = np.stack([-t_hat[..., 1], t_hat[..., 0]], -1)
        c, r = ar[1], ar[2]
        sd = ((c - p0) * n).sum(-1)
        tt = ((c - p0) * t_hat).sum(-1)
        # towards the line from the centre (either way when the line runs
        # through the centre: both points are r from it)
        side = np.where(sd != 0, -np.sign(sd), 1.0)
        for sg in (-1, 1):
            # circle point closest to / farthest from the line along -sign(sd) n
            dirn = side[..., None] * n * sg
            x = c + r * dirn
            ang = np.arctan2(dirn[..., 1], dirn[..., 0])
            ok = (tt >= 0) & (tt <= L) & _on_arc(ang, ar[3], ar[4])
            dist = np.abs(((x - p0) * n).sum(-1))
            d = np.where(ok, np.minimum(d, dist), d)
    return d


def min_distance(pair: Pair, q) -> np.ndarray:
    """Smallest distance between the two parts' boundaries at configurations q.

    Exact on lines and arcs (zero where boundaries cross).
    """
    q = _q(q)
    sa = place_part(pair.driver, q[:, 0])
    sb = place_part(pair.follower, q[:, 1])
    d = np.full(q.shape[0], np.inf)
    for a in sa:
        for b in sb:
            d = np.minimum(d, np.where(_crosses(a, b), 0.0, _seg_dist(a, b)))
    return d
