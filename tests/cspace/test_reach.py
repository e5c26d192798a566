"""``Part.reach`` (the characteristic length of a rotating part, read for
every variant a batch builds) computes every distance on arrays at once: the
same numbers, bit for bit, as one point at a time with the same functions."""

import math

import numpy as np
import pytest

from cspace.geometry import Arc, Line, Loop, Part, Rotation, Translation, trusted


def reach_one_at_a_time(part) -> float:
    cx, cy = (float(v) for v in part.axis.center)
    r = 0.0
    for lp in part.loops:
        for s in lp.segments:
            if isinstance(s, Line):
                (ax, ay), (bx, by) = s.start, s.end
                r = max(r, np.hypot(float(ax) - cx, float(ay) - cy),
                        np.hypot(float(bx) - cx, float(by) - cy))
            else:
                vx, vy = float(s.center[0]) - cx, float(s.center[1]) - cy
                d = float(np.hypot(vx, vy))
                if d == 0.0 or s.contains_angle(math.atan2(vy, vx)):
                    r = max(r, d + s.radius)
                else:
                    p0, p1 = s.start_point, s.end_point
                    r = max(r, float(np.hypot(p0[0] - cx, p0[1] - cy)),
                            float(np.hypot(p1[0] - cx, p1[1] - cy)))
    return float(r)


def test_random_arc_profiles():
    rng = np.random.default_rng(3)
    built = 0
    for _ in range(400):
        c, a0 = rng.uniform(-5, 5, 2), rng.uniform(-7, 7)
        ccw = bool(rng.integers(2))
        sweep = rng.uniform(0.3, 6.2) * (1 if ccw else -1)
        arc = Arc(tuple(c), rng.uniform(0.5, 3), a0, a0 + sweep, ccw)
        p0, p1 = arc.start_point, arc.end_point
        try:
            part = Part("p", (Loop((arc, Line(tuple(p1), tuple(p0)))),),
                        Rotation(tuple(rng.uniform(-1, 1, 2))))
        except ValueError:
            continue          # a clockwise loop: not a part
        built += 1
        assert part.reach() == reach_one_at_a_time(part)
    assert built > 100


@pytest.mark.parametrize("name", ["geneva", "reciprocating_cam", "optical_filter",
                                  "eccentric_cam"])
def test_the_models_variants(models, name):
    from synthesis.verify import box_samples
    m = models[name]
    n = 0
    for u in box_samples(m.nominal, 3 * m.tol, 60, seed=1):
        try:
            with trusted():
                b = m.build(u)
        except ValueError:
            continue
        for pair in getattr(b, "pairs", (b,)):
            for part in pair.parts:
                if isinstance(part.axis, Rotation):
                    n += 1
                    assert part.reach() == reach_one_at_a_time(part)
    assert n > 0


def test_a_circle_about_its_centre_and_a_translating_part():
    circle = Arc((0.0, 0.0), 2.0, 0.0, 2 * math.pi, True)
    assert Part("c", (Loop((circle,)),), Rotation((0.0, 0.0))).reach() == 2.0
    sq = Loop((Line((0, 0), (3, 0)), Line((3, 0), (3, 4)), Line((3, 4), (0, 4)),
               Line((0, 4), (0, 0))))
    assert Part("s", (sq,), Translation((1.0, 0.0))).reach() == 5.0
