"""Graph-based free-space matcher: does a variant's free space have the nominal
topology?

The operating channel is the free face that contains a start configuration.  Its
boundary (pieces of contact curves labelled by feature pair and branch, joined at
vertices) is a networkx multigraph; two channels match when these graphs are
isomorphic with label-, branch- and side-preserving edge matches.  When they do
not, the change is named and located:

* ``CHANNEL_CLOSED``: the nominal channel is split in the variant (a lower and an
  upper curve cross; [Tolerance synthesis] Fig. 4b), or the start is blocked;
* ``NEW_COMPONENT``: a free component separate from the channel appears where the
  nominal channel was (two curves separated); pockets elsewhere in blocked space
  cannot be reached and are not reported;
* ``SEQUENCE_CHANGED``: the contact sequence along the channel differs (a curve
  appears or vanishes, or the order changes).

With the motions (``paths``), the contact sequence is compared along them:
the curves that bound the cells each motion passes through, below and above
the follower, in the order the motion meets them (:func:`motion_sequence`).
The boundary graph of the whole region would also compare where pieces of
those curves end outside the channel: a Geneva variant whose lock arc's piece
ended at the slot corner instead of beyond it (its motion bounded by the same
contacts in the same order, its output within d) counted as changed.
"""

from __future__ import annotations

import enum
from collections import Counter
from dataclasses import dataclass, field

import networkx as nx
import numpy as np
from networkx.algorithms.isomorphism import categorical_multiedge_match

from .errors import InputError
from .freespace import ConfigurationSpace, Status, UnionFind
from .geom2d import wrap_pi
from .metric import driver_scale
from .tolerances import SLACK

__all__ = ["ChangeKind", "TopologyChange", "MatchResult", "match", "channel_graph",
           "operating_face", "motion_sequence", "closed_motion", "whole_turns", "same_place",
           "same_cycle"]


class ChangeKind(enum.Enum):
    CHANNEL_CLOSED = "channel closed"
    NEW_COMPONENT = "new free component"
    SEQUENCE_CHANGED = "contact sequence changed"


@dataclass(frozen=True)
class TopologyChange:
    """One topology change and where it happens."""

    kind: ChangeKind
    q: tuple            #: a representative configuration (q1, q2)
    q1_range: tuple     #: driver range involved
    labels: tuple       #: feature-pair labels of the curves involved
    detail: str = ""

    def to_dict(self) -> dict:
        return {"kind": self.kind.value, "q": list(self.q), "q1_range": list(self.q1_range),
                "labels": list(self.labels), "detail": self.detail}


@dataclass(frozen=True)
class MatchResult:
    """Outcome of matching a variant's channel against the nominal one."""

    same: bool
    changes: tuple
    isomorphic: bool
    nominal_face: int
    variant_face: int
    stats: dict = field(default_factory=dict)

    def __repr__(self):
        if self.same:
            return "<MatchResult: same topology>"
        return "<MatchResult: " + "; ".join(f"{c.kind.value} at q1 = {c.q[0]:.5g}"
                                             for c in self.changes) + ">"

    def to_dict(self) -> dict:
        return {"same": self.same, "isomorphic": self.isomorphic,
                "changes": [c.to_dict() for c in self.changes], "stats": dict(self.stats)}


def operating_face(cs: ConfigurationSpace, q_start) -> int:
    """The free face containing the start configuration (-1 if it is blocked)."""
    q = np.atleast_2d(np.asarray(q_start, dtype=float))
    st = cs.classify(q)[0]
    if st == Status.BLOCKED:
        return -1
    eps = SLACK
    f = int(cs.face_at(q)[0])
    if not cs.faces.get(f, False):  # on a contact: step into the free side
        for d in ((0, eps), (0, -eps), (eps, 0), (-eps, 0)):
            g = int(cs.face_at(q + np.array(d))[0])
            if cs.faces.get(g, False):
                return g
        return -1
    return f


def _bounding(cs: ConfigurationSpace, cells):
    """Per (curve, free_above): the mid-points of the slabs where that side of the
    curve bounds one of ``cells`` ((slab, cell) pairs)."""
    out: dict = {}
    ev = cs.events
    for k, j in cells:
        c = cs.cells[k][j]
        m = 0.5 * (ev[k] + ev[k + 1])
        if c.lower >= 0:
            out.setdefault((c.lower, True), []).append(m)
        if c.upper >= 0:
            out.setdefault((c.upper, False), []).append(m)
    return {key: np.array(v) for key, v in out.items()}


def channel_graph(cs: ConfigurationSpace, face: int, resolution: float = 0.0,
                  cells=None) -> nx.MultiGraph:
    """Boundary graph of one free face: the edges of ``cs.graph`` bounding it.

    With ``resolution`` > 0, boundary pieces that last less than it of driver
    motion (radians, or a length over the pair's characteristic length) are
    contracted to a vertex: such a contact is an instant of the motion, not a
    step of its contact sequence.

    With ``cells`` (an iterable of (slab, cell), e.g. the cells a motion passes
    through, :attr:`SimulationResult.cells`), only the pieces that bound one of
    them are kept: the boundary of the operating region."""
    H = nx.MultiGraph()
    near = None if cells is None else _bounding(cs, cells)
    for u, v, k, d in cs.graph.edges(keys=True, data=True):
        if d["free_face"] != face:
            continue
        if near is not None:
            mids = near.get((d["curve"], d["free_above"]))
            a, b = d["q1_range"]
            if mids is None or not np.any((mids >= a) & (mids <= b)):
                continue
        H.add_edge(u, v, key=k, **d)
    if resolution > 0:
        s1 = 1.0 / driver_scale(cs.pair)
        uf = UnionFind(cs.graph.number_of_nodes())
        keep = []
        for u, v, k, d in H.edges(keys=True, data=True):
            a, b = d["q1_range"]
            if abs(b - a) * s1 < resolution:
                uf.union(u, v)
            else:
                keep.append((u, v, k, d))
        H = nx.MultiGraph()
        for u, v, k, d in keep:
            H.add_edge(uf.find(u), uf.find(v), key=k, **d)
    return H


def motion_sequence(cs: ConfigurationSpace, sim, resolution: float = 0.0, *,
                    cyclic: bool = False) -> tuple:
    """The contact sequence along a motion: the curves bounding the cells it
    passes through, below and above the follower, in order.

    Returns ``(lower, upper)``, each a tuple of ``(label, branch)`` (``("", 0)``
    for a window edge) in the order the motion meets them, consecutive equal
    entries merged; contacts that last less than ``resolution`` of driver
    motion (C-space metric) are contracted first.

    With ``cyclic`` (a motion that ends where it starts, :func:`closed_motion`)
    the sequence is a cycle: the contact the motion ends on and the one it
    starts on are one contact when they are the same curve (their durations
    added before the contraction), and it is given once, first.  Compare
    cycles with :func:`same_cycle`.
    """
    return tuple(tuple(k for k, _ in side)
                 for side in _motion_runs(cs, sim, resolution, cyclic=cyclic))


#: :func:`closed_motion`: how far (a share of the follower window's span, or of
#: 1 when smaller) the follower may end from where it started.
CLOSED_TOL = 1e-9


def closed_motion(cs: ConfigurationSpace, sim) -> bool:
    """Whether ``sim`` is a motion of whole turns of a turning driver that
    ends where it started: the follower back at its start (on the same place
    of its turn when it turns too), as a cam's follower is after a turn of
    the cam, and unlike a Geneva wheel, which a turn of the driver indexes
    on.

    Such a motion repeats, and its start is only where the drawing happens
    to begin it: its contact sequence is a cycle (:func:`motion_sequence`
    with ``cyclic``).  Compared as a line, a variant whose hand-over between
    two contacts moves across the start (a disc drawn as two arcs joined
    where the follower rests at the start) reads as changed although its
    motion is the same."""
    q2 = np.asarray(getattr(sim, "q2", ()), dtype=float)
    return (whole_turns(cs, sim) and len(q2) == len(sim.q1)
            and bool(same_place(cs, q2[-1], q2[0])))


def whole_turns(cs: ConfigurationSpace, sim) -> bool:
    """Whether ``sim`` completed a drive of whole turns (one or more) of a
    turning driver."""
    q1 = np.asarray(getattr(sim, "q1", ()), dtype=float)
    if not (cs.periodic[0] and getattr(sim, "success", False) and len(q1) > 1):
        return False
    turns = (q1[-1] - q1[0]) / (2 * np.pi)
    return bool(round(turns) != 0 and abs(turns - round(turns)) <= 1e-9 * max(1.0, abs(turns)))


def same_place(cs: ConfigurationSpace, a, b):
    """Whether follower positions ``a`` and ``b`` (arrays broadcast) are the
    same place, to :data:`CLOSED_TOL` of the follower window's span (or of 1
    when smaller); on its turn for a turning follower."""
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    if cs.periodic[1]:
        d = wrap_pi(d)
    return np.abs(d) <= CLOSED_TOL * max(1.0, abs(float(cs.window[3] - cs.window[2])))


def cycle_form(seq) -> tuple:
    """A contact sequence read as a cycle (its last entry dropped when it is
    its first: the contact that ends the motion is the one that starts it),
    turned to begin at its least rotation, so that two cycles are the same
    exactly when their forms are equal."""
    seq = tuple(seq)
    if len(seq) > 1 and seq[0] == seq[-1]:
        seq = seq[:-1]
    if len(seq) < 2:
        return seq
    return min(seq[k:] + seq[:k] for k in range(len(seq)))


def same_cycle(a, b) -> bool:
    """Whether two contact sequences (:func:`motion_sequence`) are the same
    cycle: equal up to where the cycle is begun."""
    return cycle_form(a) == cycle_form(b)


def _motion_runs(cs: ConfigurationSpace, sim, resolution: float = 0.0,
                 cyclic: bool = False) -> tuple:
    """:func:`motion_sequence` with the driver value (unwrapped, as the
    motion's ``q1``) where each of its contacts begins: ``(lower, upper)``,
    each a tuple of ``((label, branch), q1)``; with ``cyclic`` the contact
    the motion ends on, when it is the one it starts on, is that one (its
    duration added to it) and is not repeated."""
    ev = cs.events
    s1 = 1.0 / driver_scale(cs.pair)
    cells = tuple(sim.cells)
    n = len(cells)
    q1 = np.asarray(sim.q1, dtype=float)
    lo1, hi1 = cs.window[0], cs.window[1]

    def wrapped(x):
        return (x - lo1) % (hi1 - lo1) + lo1 if cs.periodic[0] else x

    dur = []
    for p, (k, _) in enumerate(cells):
        if n == 1 and len(q1):
            # one cell all along (a turn of the driver in one slab): the
            # drive's own length (its wrapped ends may coincide)
            dur.append(abs(float(q1[-1] - q1[0])) * s1)
            continue
        a, b = float(ev[k]), float(ev[k + 1])
        if p == 0 and len(q1):
            x = float(wrapped(q1[0]))
            a, b = (x, b) if q1[-1] >= q1[0] else (a, x)
        if p == n - 1 and len(q1) and n > 1 or (n == 1 and len(q1)):
            x = float(wrapped(q1[-1]))
            if q1[-1] >= q1[0]:
                b = x if x >= a else b
            else:
                a = x if x <= b else a
        dur.append(abs(b - a) * s1)
    # where each cell begins along the drive (driver units, unwrapped)
    way = 1.0 if not len(q1) or q1[-1] >= q1[0] else -1.0
    at = (float(q1[0]) if len(q1) else 0.0) + way * np.concatenate(
        [[0.0], np.cumsum(dur)[:-1]]) / s1 if n else np.zeros(0)
    out = []
    for side in ("lower", "upper"):
        ids = []
        for k, j in cells:
            c = getattr(cs.cells[k][j], side)
            ids.append(("", 0) if c < 0 else (cs.curves[c].label, cs.curves[c].branch))
        runs = []
        for key, d, x in zip(ids, dur, at):
            if runs and runs[-1][0] == key:
                runs[-1][1] += d
            else:
                runs.append([key, d, float(x)])
        if cyclic and len(runs) > 1 and runs[0][0] == runs[-1][0]:
            # the contact the motion ends on goes on where it starts
            runs[0][1] += runs.pop()[1]
        seq = []
        for key, d, x in runs:
            if d >= resolution and (not seq or seq[-1][0] != key):
                seq.append((key, x))
        if cyclic and len(seq) > 1 and seq[0][0] == seq[-1][0]:
            seq.pop()
        out.append(tuple(seq))
    return tuple(out)


def _probes(cs: ConfigurationSpace, face: int, cells=None):
    """Centres of the free cells of a face (or of those of ``cells`` in it):
    (N, 2) configurations and (slab, cell)."""
    lo2, hi2 = cs.window[2], cs.window[3]
    if cells is None:
        where = [(k, j) for k, row in enumerate(cs.cells) for j, c in enumerate(row)
                 if c.face == face]
    else:
        where = sorted({(int(k), int(j)) for k, j in cells if cs.cells[k][j].face == face})
    if not where:
        return np.zeros((0, 2)), where
    m = np.array([0.5 * (cs.events[k] + cs.events[k + 1]) for k, _ in where])
    cells = [cs.cells[k][j] for k, j in where]
    lo = np.full(len(cells), float(lo2))
    hi = np.full(len(cells), np.nan)
    # every bounding curve evaluated once, at all the mid-points it bounds
    for out, idx in ((lo, np.array([c.lower for c in cells])),
                     (hi, np.array([c.upper for c in cells]))):
        for i in np.unique(idx[idx >= 0]):
            sel = np.nonzero(idx == i)[0]
            out[sel] = cs.curves[int(i)].evaluate(m[sel])
    for t, c in enumerate(cells):
        if c.upper < 0:
            hi[t] = hi2 if not cs.periodic[1] else lo[t] + 2 * np.pi
        if cs.periodic[1]:
            if len(cs.cells[where[t][0]]) == 1:
                lo[t], hi[t] = lo2, hi2
            hi[t] = lo[t] + (hi[t] - lo[t]) % (2 * np.pi)
    return np.column_stack([m, 0.5 * (lo + hi)]), where


def match(nominal: ConfigurationSpace, variant: ConfigurationSpace, q_start, *,
          resolution: float = 0.0, paths=None, variant_start=None) -> MatchResult:
    """Compare the variant's operating channel with the nominal one.

    Parameters
    ----------
    nominal, variant : ConfigurationSpace
        C-spaces of the nominal pair and of a variant, over the same window.
    q_start : (q1, q2)
        A configuration inside the nominal operating channel.
    resolution : float
        Boundary pieces that last less than this of driver motion (C-space
        metric) are contracted before the contact sequences are compared (see
        :func:`channel_graph`): a contact that lasts 1e-5 rad where two contacts
        hand over at a near-tangency is an instant, not a change of sequence;
        what it does to the output (a jump of the follower) is the deviation
        test's to judge.  Channel closures and new components are found by
        probing and are not affected.
    paths : (SimulationResult, SimulationResult), optional
        The nominal and the variant motion (:func:`cspace.simulate.simulate`).
        With them only the operating region is compared: the cells each motion
        passes through (:attr:`SimulationResult.cells`) and the curve pieces
        bounding them.  A free pocket that the motion never enters (for a
        Geneva wheel, a configuration a slot width away from any indexing
        position) may then split off or change its contacts without the variant
        counting as changed: it cannot jam or drive the follower wrongly.
        Without ``paths`` the whole free face containing ``q_start`` is compared.
    variant_start : (q1, q2), optional
        Where the variant's follower starts, when not at ``q_start``: the
        point of its free interval nearest to the stated start
        (:func:`cspace.defects.assembled_start`).  Default ``q_start``.
    """
    from .argcheck import getscalar
    resolution = getscalar(resolution, "resolution", nonneg=True)
    cells0, cells1 = _path_cells(nominal, variant, paths)
    f0 = operating_face(nominal, q_start)
    if f0 < 0:
        raise InputError(f"q_start {tuple(q_start)} is not in the nominal free space")
    f1 = operating_face(variant, q_start if variant_start is None else variant_start)
    if f1 < 0:
        change = TopologyChange(ChangeKind.CHANNEL_CLOSED, tuple(map(float, q_start)),
                                (float(q_start[0]), float(q_start[0])), (),
                                "the start configuration is blocked in the variant")
        return MatchResult(False, (change,), False, f0, f1, {})
    changes = []
    # 1. split: nominal channel probes in different variant free faces
    P, where, faces_hit = _split(nominal, variant, f0, cells0, changes)
    main_face = faces_hit.most_common(1)[0][0] if faces_hit else f1
    # 2. new components near the channel
    _new_components(nominal, variant, f0, cells0, where, faces_hit, main_face, changes)
    # 3. contact sequence of the channel
    if paths is not None:
        return _sequence_change(nominal, variant, paths, resolution, changes, q_start, f0,
                                main_face, len(P))
    H0 = channel_graph(nominal, f0, resolution, cells0)
    H1 = channel_graph(variant, main_face, resolution, cells1)
    em = categorical_multiedge_match(["label", "branch", "free_above"], [None, None, None])
    iso = nx.is_isomorphic(H0, H1, edge_match=em)
    if not iso and not changes:
        changes.append(_graph_change(nominal, H0, H1, q_start))
    stats = {"nominal_edges": H0.number_of_edges(), "variant_edges": H1.number_of_edges(),
             "probes": int(len(P))}
    return MatchResult(not changes, tuple(changes), bool(iso), f0, main_face, stats)


def _path_cells(nominal, variant, paths):
    """The cells each motion of ``paths`` visits (None, None without paths),
    checked against the C-spaces."""
    if paths is None:
        return None, None
    try:
        p0, p1 = paths
        cells0, cells1 = tuple(p0.cells), tuple(p1.cells)
    except (TypeError, ValueError, AttributeError):
        raise InputError("paths must be a pair (nominal, variant) of SimulationResult, "
                         f"got {type(paths).__name__}", name="paths") from None
    for cs, cells, nm in ((nominal, cells0, "nominal"), (variant, cells1, "variant")):
        for kj in cells:
            k, j = kj
            if not (0 <= k < len(cs.cells) and 0 <= j < len(cs.cells[k])):
                raise InputError(f"the {nm} path visits cell {tuple(kj)}, which its "
                                 "C-space does not have: pass the motions simulated "
                                 "in these C-spaces", name="paths")
    return cells0, cells1


def _split(nominal, variant, f0, cells0, changes):
    """Stage 1 of :func:`match`: probe the nominal channel; probes in
    different free faces of the variant mean the channel split (a change is
    appended).  Returns the probes, the nominal cells they lie in, and the
    variant's free faces they hit (a Counter)."""
    P, where = _probes(nominal, f0, cells0)
    vf = variant.face_at(P) if len(P) else np.zeros(0, int)
    vfree = np.array([variant.faces.get(int(f), False) for f in vf], dtype=bool)
    faces_hit = Counter(int(f) for f, fr in zip(vf, vfree) if fr)
    if len(faces_hit) > 1:
        # locate the split: the first two free probes (in q1, the blocked
        # ones between them skipped) whose variant faces differ; the channel
        # closes between them, at the blocked probes if there are any (a
        # channel that closes over a stretch of the motion blocks the probes
        # there), else half-way
        order = np.argsort(P[:, 0], kind="stable")
        i0 = i1 = int(order[0])
        blocked = []
        last = None
        for i in order.tolist():
            if not vfree[i]:
                if last is not None:
                    blocked.append(i)
                continue
            if last is not None and vf[i] != vf[last]:
                i0, i1 = last, i
                break
            last, blocked = i, []
        else:
            blocked = []
        if blocked:
            x = 0.5 * (P[blocked[0], 0] + P[blocked[-1], 0])
            y = float(P[blocked[len(blocked) // 2], 1])
        else:
            x, y = 0.5 * (P[i0, 0] + P[i1, 0]), float(P[i0, 1])
        # the probes lie at cell centres, far apart: the channel's mid-line
        # between them, sampled finely, leaves the first component where
        # the channel closes
        lo1, hi1 = float(P[i0, 0]), float(P[i1, 0])
        got = _leaves_face(nominal, variant, where, P[i0], P[i1], int(vf[i0]))
        if got is not None:
            x, y, lo1, hi1 = got
        labels = _labels_near(variant, x, y)
        changes.append(TopologyChange(ChangeKind.CHANNEL_CLOSED, (float(x), y),
                                      (lo1, hi1), labels,
                                      f"the nominal channel falls into {len(faces_hit)} "
                                      "separate free components"))
    return P, where, faces_hit


#: :func:`_leaves_face`: samples of the nominal channel's mid-line between
#: two probes.
SPLIT_SAMPLES = 64


def _leaves_face(nominal, variant, where, p0, p1, face: int):
    """Where the nominal channel's mid-line, from probe ``p0`` (in the
    variant's free face ``face``) towards probe ``p1``, first leaves that
    face: ``(q1, q2, q1 before, q1 at)`` between two of
    :data:`SPLIT_SAMPLES` samples, or None (no nominal cell of ``where``
    spans a sample, or the line never leaves the face)."""
    xs = np.linspace(float(p0[0]), float(p1[0]), SPLIT_SAMPLES + 1)[1:]
    ev = nominal.events
    pts = []
    for x in xs:
        k = int(np.clip(np.searchsorted(ev, x, side="right") - 1, 0, len(ev) - 2))
        cells = [nominal.cells[kk][j] for kk, j in where if kk == k]
        if not cells:
            return None
        mids = []
        for c in cells:
            lo = (nominal.curves[c.lower].evaluate(np.array([x]))[0] if c.lower >= 0
                  else nominal.window[2])
            hi = (nominal.curves[c.upper].evaluate(np.array([x]))[0] if c.upper >= 0
                  else nominal.window[3])
            if nominal.periodic[1]:
                hi = lo + (hi - lo) % (2 * np.pi)
            mids.append(0.5 * (lo + hi))
        # the cell of the slab nearest the line between the probes
        t = (x - p0[0]) / max(p1[0] - p0[0], 1e-300)
        want = p0[1] + t * (p1[1] - p0[1])
        pts.append((x, min(mids, key=lambda m: abs(m - want))))
    Q = np.array(pts, dtype=float)
    if variant.periodic[1]:
        lo2 = variant.window[2]
        Q[:, 1] = (Q[:, 1] - lo2) % (2 * np.pi) + lo2
    f = variant.face_at(Q)
    out = np.nonzero(f != face)[0]
    if not len(out):
        return None
    j = int(out[0])
    before = float(xs[j - 1]) if j else float(p0[0])
    return float(xs[j]), float(Q[j, 1]), before, float(xs[j])


def _new_components(nominal, variant, f0, cells0, where, faces_hit, main_face, changes):
    """Stage 2 of :func:`match`: variant free faces carved out of the nominal
    channel (most of their probes inside it) are new components (appended to
    ``changes``); free pockets elsewhere cannot be reached from the channel
    and do not change the motion."""
    region = None if cells0 is None else set(where)
    for g in sorted(f for f, fr in variant.faces.items() if fr and f != main_face):
        if g in faces_hit:
            continue
        G, _ = _probes(variant, g)
        if not len(G):
            continue
        if cells0 is None:
            inside = nominal.face_at(G) == f0
        else:
            sl, ci = nominal.cell_at(G)
            inside = np.array([(int(a), int(b)) in region for a, b in zip(sl, ci)], dtype=bool)
        if len(inside) and np.mean(inside) >= 0.5:
            c = G[len(G) // 2]
            changes.append(TopologyChange(ChangeKind.NEW_COMPONENT, (float(c[0]), float(c[1])),
                                          (float(G[:, 0].min()), float(G[:, 0].max())),
                                          _labels_near(variant, c[0], c[1]),
                                          "a free component that the nominal does not have"))


#: How a message names the "curve" of a cell that no contact bounds (label
#: ``""``: the follower's window edge, where it is free to move on).
NO_CONTACT = "none (window edge)"


def contact_name(label: str) -> str:
    """A curve label for a message: the window edge (``""``) named."""
    return label or NO_CONTACT


def _named(labels) -> list:
    """Curve labels for a message, sorted, the window edge named."""
    return [contact_name(lab) for lab in sorted(labels)]


def _graph_change(nominal, H0, H1, q_start) -> TopologyChange:
    """Stage 3 of :func:`match` without motions: the channel graphs differ;
    what vanished or appeared, and where."""
    l0 = Counter((d["label"], d["branch"]) for _, _, d in H0.edges(data=True))
    l1 = Counter((d["label"], d["branch"]) for _, _, d in H1.edges(data=True))
    gone = list((l0 - l1).elements())
    new = list((l1 - l0).elements())
    if gone or new:
        detail = (f"curves vanished: {_named({g[0] for g in gone})}; " if gone else "") + \
                 (f"curves appeared: {_named({n[0] for n in new})}" if new else "")
        labs = tuple(sorted({g[0] for g in gone} | {n[0] for n in new}))
    else:
        detail = "the same curves bound the channel in a different order"
        labs = ()
    xs = [d["q1_range"] for _, _, d in H1.edges(data=True) if (d["label"], d["branch"]) in
          set(new)] or [d["q1_range"] for _, _, d in H0.edges(data=True)
                        if (d["label"], d["branch"]) in set(gone)]
    if xs:
        lo = float(min(r[0] for r in xs))
        hi = float(max(r[1] for r in xs))
    else:
        lo, hi = float(nominal.window[0]), float(nominal.window[1])
    x = 0.5 * (lo + hi)
    return TopologyChange(ChangeKind.SEQUENCE_CHANGED, (x, float(q_start[1])), (lo, hi), labs,
                          detail)


def _sequence_change(nominal, variant, paths, resolution, changes, q_start, f0, main_face,
                     nprobes) -> MatchResult:
    """Step 3 of :func:`match` with motions: compare their contact sequences."""
    # a motion that ends where it starts repeats: its sequence is a cycle
    cyclic = closed_motion(nominal, paths[0])
    r0 = _motion_runs(nominal, paths[0], resolution, cyclic)
    r1 = _motion_runs(variant, paths[1], resolution, cyclic)
    s0 = tuple(tuple(k for k, _ in side) for side in r0)
    s1 = tuple(tuple(k for k, _ in side) for side in r1)
    same_side = [same_cycle(a, b) if cyclic else a == b for a, b in zip(s0, s1)]
    same_seq = all(same_side)
    if not same_seq and not changes:
        which = "below" if not same_side[0] else "above"
        i = 0 if which == "below" else 1
        a, b = s0[i], s1[i]
        gone = sorted({g[0] for g in a} - {g[0] for g in b})
        new = sorted({g[0] for g in b} - {g[0] for g in a})
        named = sorted(set(gone) | set(new))
        if gone or new:
            detail = (f"curves vanished: {_named(gone)}; " if gone else "") + \
                     (f"curves appeared: {_named(new)}" if new else "")
        else:
            detail = "the same curves bound the channel in a different order"
            k = next((j for j, (p, q) in enumerate(zip(a, b)) if p != q), min(len(a), len(b)))
            if k < len(a) and k < len(b):
                # the first contact that differs, in drive order
                detail += (f": contact {k + 1} of the nominal's sequence is "
                           f"{contact_name(a[k][0])!r}, the variant's {contact_name(b[k][0])!r}")
                named = sorted({a[k][0], b[k][0]})
            elif len(a) != len(b):
                detail += (f": {len(a)} contacts in the nominal's sequence, {len(b)} in the "
                           "variant's")
        detail = f"{detail} ({which} the follower)"
        x, y = _first_difference(r0[i], r1[i], paths[1], q_start)
        changes = changes + [TopologyChange(
            ChangeKind.SEQUENCE_CHANGED, (x, y),
            (float(nominal.window[0]), float(nominal.window[1])),
            tuple(named), detail)]
    stats = {"nominal_sequence": [len(s0[0]), len(s0[1])],
             "variant_sequence": [len(s1[0]), len(s1[1])], "probes": int(nprobes),
             "cyclic": bool(cyclic)}
    return MatchResult(not changes, tuple(changes), bool(same_seq), f0, main_face, stats)


def _first_difference(runs0, runs1, sim, q_start) -> tuple:
    """Where along the drive two contact sequences (:func:`_motion_runs` of
    one side) first differ: the earlier beginning, in drive order, of their
    first unequal contacts, and the variant's follower there (its motion
    ``sim``); the drive's start when that cannot be placed."""
    k = 0
    while k < min(len(runs0), len(runs1)) and runs0[k][0] == runs1[k][0]:
        k += 1
    starts = [r[k][1] for r in (runs0, runs1) if k < len(r)]
    q1 = np.asarray(sim.q1, dtype=float)
    q2 = np.asarray(sim.q2, dtype=float)
    if not starts or len(q1) < 2:
        return float(q_start[0]), float(q_start[1])
    way = 1.0 if q1[-1] >= q1[0] else -1.0
    x = way * min(way * s for s in starts)
    order = np.argsort(way * q1, kind="stable")
    return float(x), float(np.interp(way * x, way * q1[order], q2[order]))


def _labels_near(cs: ConfigurationSpace, q1, q2) -> tuple:
    return tuple(lab for lab in cell_labels(cs, q1, q2) if lab is not None)


def cell_labels(cs: ConfigurationSpace, q1, q2) -> tuple:
    """The labels of the contact curves below and above the cell of ``cs``
    that holds (q1, q2): ``(lower, upper)``, None for a window edge."""
    slabs, ci = cs.cell_at(np.array([[q1, q2]], dtype=float))
    c = cs.cells[int(slabs[0])][int(ci[0])]
    return tuple(cs.curves[i].label if i >= 0 else None for i in (c.lower, c.upper))
