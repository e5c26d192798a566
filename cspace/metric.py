"""The C-space metric: how driver and follower coordinates are measured alike.

A pair's coordinates are angles (rad) for rotating parts and slides (model
length units) for sliding ones.  To compare them, and to state one tolerance
for both, a slide counts in *characteristic lengths*: ``L =
pair.char_length``, the largest reach of a rotating part about its axis (for
a pair with no rotating part, the size of the parts).  A slide of ``L``
counts as one radian, because a part of reach ``L`` turned by one radian moves
its far points by ``L``.  Every accuracy setting (:class:`cspace.accuracy.Accuracy`),
deviation threshold and margin of the library is stated in this metric.

:func:`coord_scale` is the formula; :func:`driver_scale` and
:func:`follower_scale` apply it to a pair's coordinates.  :func:`wrap_to` and
:func:`split_wrapped` place a rotating follower's angles in the C-space
window.
"""

from __future__ import annotations

import math

import numpy as np

from .geom2d import TWO_PI
from .geometry import Rotation

__all__ = ["coord_scale", "driver_scale", "follower_scale", "wrap_to", "split_wrapped"]


def coord_scale(axis, L: float) -> float:
    """Length of a coordinate that counts as 1 in the C-space metric: 1 for a
    rotation (rad), the characteristic length ``L`` for a slide."""
    return 1.0 if isinstance(axis, Rotation) else L


def driver_scale(pair) -> float:
    """:func:`coord_scale` of the pair's driver coordinate."""
    return coord_scale(pair.driver.axis, pair.char_length)


def follower_scale(pair) -> float:
    """:func:`coord_scale` of the pair's follower coordinate."""
    return coord_scale(pair.follower.axis, pair.char_length)


def wrap_to(x, lo):
    """Angles ``x`` wrapped into ``[lo, lo + 2 pi)``."""
    return (x - lo) % TWO_PI + lo


def split_wrapped(pl, lo, periodic: bool) -> list:
    """A polyline ``pl`` (M, 2) of (q1, q2) split where a rotating follower's
    angle q2, wrapped into ``[lo, lo + 2 pi)``, jumps by more than pi (and
    pieces of fewer than two points dropped); the polyline itself when the
    follower is not ``periodic``."""
    if not periodic:
        return [pl]
    v = wrap_to(pl[:, 1], lo)
    jumps = np.nonzero(np.abs(np.diff(v)) > math.pi)[0]
    segs = []
    start = 0
    for j in jumps:
        seg = np.stack([pl[start:j + 1, 0], v[start:j + 1]], 1)
        segs.append(seg)
        start = j + 1
    segs.append(np.stack([pl[start:, 0], v[start:]], 1))
    return [s for s in segs if len(s) >= 2]
