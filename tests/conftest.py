"""Shared fixtures: built-in models, their C-spaces (computed once per session),
and an independent brute-force overlap reference built on shapely polygons."""


import os

import numpy as np
import pytest

from cspace.geometry import Rotation

try:
    from hypothesis import settings as _hsettings
except ImportError:  # pragma: no cover - hypothesis is a test extra
    _hsettings = None
if _hsettings is not None:
    # property tests draw the same examples on every run, so that a run on a
    # fresh machine fails only where the code changed; HYPOTHESIS_PROFILE=explore
    # draws new ones (and keeps any failure it finds in .hypothesis/)
    _hsettings.register_profile("repeatable", derandomize=True, database=None)
    _hsettings.register_profile("explore", derandomize=False)
    _hsettings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "repeatable"))


@pytest.fixture(scope="session")
def models():
    from mechanisms.models import BUILTIN
    return {k: f() for k, f in BUILTIN.items()}


@pytest.fixture(scope="session")
def cspaces(models):
    from mechanisms.analysis import model_cspaces
    return {k: model_cspaces(m) for k, m in models.items()}


def _part_geom(part, per_turn=720):
    """The part's material as a shapely geometry at q = 0, arcs finely sampled."""
    from shapely.geometry import Polygon
    geom = None
    for lp in part.loops:
        poly = Polygon(lp.sample(per_turn))
        geom = poly if geom is None else geom.symmetric_difference(poly)
    return geom


def _move_coords(axis, q, coords):
    if isinstance(axis, Rotation):
        c = np.asarray(axis.center)
        cq, sq = np.cos(q)[:, None], np.sin(q)[:, None]
        x, y = coords[..., 0] - c[0], coords[..., 1] - c[1]
        return np.stack([c[0] + cq * x - sq * y, c[1] + sq * x + cq * y], -1)
    e = np.asarray(axis.direction)
    return coords + q[:, None, None] * e


def brute_overlap(pair, q, per_turn=720):
    """Independent overlap test: shapely polygons (arcs with ``per_turn`` points per
    full circle), moved per configuration, tested with ``shapely.intersects``."""
    import shapely
    q = np.atleast_2d(np.asarray(q, dtype=float))
    n = len(q)
    out = []
    for part, qq in ((pair.driver, q[:, 0]), (pair.follower, q[:, 1])):
        g = _part_geom(part, per_turn)
        coords = shapely.get_coordinates(g)
        k = len(coords)
        arr = np.full(n, g, dtype=object)
        moved = _move_coords(part.axis, qq, np.broadcast_to(coords, (n, k, 2)))
        out.append(shapely.set_coordinates(shapely.from_wkb(shapely.to_wkb(arr)),
                                           moved.reshape(-1, 2)))
    return shapely.intersects(out[0], out[1])
