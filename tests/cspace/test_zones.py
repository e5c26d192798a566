
import concurrent.futures

import numpy as np
import pytest

from cspace.defects import reference
from cspace.geometry import Assembly, trusted
from cspace.zones import _band_evaluator, contact_zones, varied_curve_values


@pytest.fixture(scope="module")
def recip_zones(models):
    m = models["reciprocating_cam"]
    ref = reference(m)
    return m, ref, contact_zones(ref.spaces[0], m, 0, faces=[ref.faces[0]])


def _random_box(m, n, seed):
    rng = np.random.default_rng(seed)
    U = m.nominal + m.tol * rng.uniform(-1, 1, (n, m.n))
    U[: n // 4] = m.nominal + m.tol * rng.choice([-1.0, 1.0], (n // 4, m.n))  # corners
    return U


def test_zone_containment_reciprocating_cam(recip_zones):
    """1000 seeded box vectors (a quarter of them corners): every varied curve lies
    inside its band, in the normal (C-space metric) and the vertical sense."""
    m, ref, z = recip_zones
    cs = ref.spaces[0]

    def build(u):
        with trusted():
            return m.build(u)

    evs = [(b, _band_evaluator(cs, b, build)) for b in z.bands]
    worst_n = worst_v = -np.inf
    for u in _random_box(m, 1000, 0):
        pair = build(u)
        for b, ev in evs:
            tau, _ = ev(u)
            ok = np.isfinite(tau) & np.isfinite(b.upper)
            worst_n = max(worst_n, np.max(np.maximum(tau - b.upper, b.lower - tau)[ok]))
            v = varied_curve_values(cs.curves[b.curve], pair, b.q1) - b.q2
            ok = np.isfinite(v) & np.isfinite(b.vertical_upper)
            worst_v = max(worst_v, np.max(np.maximum(v - b.vertical_upper,
                                                     b.vertical_lower - v)[ok]))
    assert worst_n <= 1e-9 and worst_v <= 1e-9


def test_zone_bands_and_linear_baseline(recip_zones):
    m, ref, z = recip_zones
    for b in z.bands:
        ok = np.isfinite(b.upper)
        assert np.all(b.upper[ok] >= -1e-12) and np.all(b.lower[ok] <= 1e-12)
        # the first-order band is of the same size as the nonlinear one here (the
        # contact equations are nearly linear in these parameters)
        np.testing.assert_allclose(b.upper[ok], b.linear_upper[ok], rtol=0.05, atol=1e-4)
        assert set(b.depends) >= {"tip_r"} and b.n_evaluated > 2 * len(b.depends)
        # the seeds are box vectors that change only the dependency set
        for u in (b.u_upper, b.u_lower):
            assert m.in_box(u)
            changed = {n for n, d in zip(m.names, u - m.nominal) if d != 0}
            assert changed <= set(b.depends)


def test_marginal_designs_show_zone_overlap(models):
    for name in ("geneva", "reciprocating_cam"):
        m = models[name]
        ref = reference(m, "fast")
        z = contact_zones(ref.spaces[0], m, 0, "fast", faces=[ref.faces[0]])
        assert z.overlaps, name
        o = z.overlaps[0]
        assert o.depth > 0 and o.q1_range[0] <= o.q[0] <= o.q1_range[1]
        assert o.lower_label != o.upper_label and set(o.depends)
        d = z.to_dict()
        assert d["overlaps"] and isinstance(d["overlaps"][0]["u_lower_curve_up"], dict)
        # the file says which numbers are in the metric and which in q2's unit,
        # and holds L to convert (it stated one metric for both)
        assert d["char_length"] == ref.spaces[0].pair.char_length
        assert set(d["fields"].values()) == {"metric", "q2's own unit: rad for a turning "
                                                       "follower, else units"}


def test_reciprocating_overlap_is_at_the_narrow_passages(recip_zones):
    m, ref, z = recip_zones
    assert len(z.overlaps) == 6  # one passage between every two cups
    for o in z.overlaps:
        assert o.gap < 0.1 and "face.right" in o.lower_label and "face.left" in o.upper_label


def test_faces_restrict_the_zones(models):
    m = models["geneva"]
    ref = reference(m, "fast")
    cs = ref.spaces[0]
    all_b = {b.curve for b in cs.boundary}
    z = contact_zones(cs, m, 0, "fast", curves=sorted(all_b)[:3])
    assert len(z.bands) == 3


def _geneva_pin_vertex_case(models, climb):
    """The Geneva pin against the lock/slot corner, near the start of the contact:
    most box corners lose the contact there, and the extreme variant is an isolated
    corner whose single-coordinate neighbours all lose it."""
    from cspace.accuracy import Accuracy
    m = models["geneva"]
    acc = Accuracy.preset("default").replace(zone_climb=climb)
    ref = reference(m, acc)
    cs = ref.spaces[0]
    ci = next(i for i, c in enumerate(cs.curves)
              if c.label == "driver:pin|wheel:lock1^slot1.right" and c.branch == 1
              and 2.3 < c.q1_start < 2.6)
    b = contact_zones(cs, m, 0, acc, curves=[ci]).bands[0]

    def build(u):
        with trusted():
            return m.build(u)

    ev = _band_evaluator(cs, b, build)
    sign = dict(zip(b.depends, (-1, -1, -1, -1, 1, 1, 1, -1, -1, -1, -1)))
    u = m.nominal + np.array([sign.get(nm, 0) for nm in m.names]) * m.tol
    return b, ev(u)[0]


def test_zone_holds_isolated_corner_near_a_curve_end(models):
    b, tau = _geneva_pin_vertex_case(models, 4)
    ok = np.isfinite(tau) & np.isfinite(b.lower)
    assert ok.sum() >= 5 and tau[ok].min() < -0.05  # the variant really moves the curve
    assert np.all(tau[ok] >= b.lower[ok] - 1e-9) and np.all(tau[ok] <= b.upper[ok] + 1e-9)


def test_zone_without_climb_misses_it(models):
    """The same band with the climb off (the ``fast`` behaviour): the first-order
    guide alone misses the variant, which the test above shows is caught."""
    b, tau = _geneva_pin_vertex_case(models, 0)
    ok = np.isfinite(tau) & np.isfinite(b.lower)
    assert np.any(tau[ok] < b.lower[ok] - 1e-3)


GENEVA_END_CURVES = (("driver:pin|wheel:slot1.left^lock2", -1),
                     ("driver:pin|wheel:lock1^slot1.right", 1),
                     ("driver:relief|wheel:lock0^slot0.right", 1))


def _excess(m, cs, bands, U, pair_index=0):
    """Largest distance of a varied curve outside its band over the vectors ``U``."""
    def build(u):
        with trusted():
            p = m.build(u)
        return p.pairs[pair_index] if isinstance(p, Assembly) else p

    worst = -np.inf
    for b in bands:
        ev = _band_evaluator(cs, b, build)
        for u in U:
            tau = ev(u)[0]
            ok = np.isfinite(tau) & np.isfinite(b.upper)
            if ok.any():
                worst = max(worst, np.max(np.maximum(tau - b.upper, b.lower - tau)[ok]))
    return worst


def test_zone_containment_geneva_curve_ends(models):
    """The Geneva curves whose trimmed ends defeat the first-order guide (the pin and
    the relief against the slot corners): at the default preset every one of 240
    seeded box vectors (a quarter corners) lies inside the bands."""
    m = models["geneva"]
    ref = reference(m, "default")
    cs = ref.spaces[0]
    pick = [i for i, c in enumerate(cs.curves) if (c.label, c.branch) in GENEVA_END_CURVES]
    bands = contact_zones(cs, m, 0, "default", curves=pick).bands
    assert len(bands) >= 3
    assert _excess(m, cs, bands, _random_box(m, 240, 3)) <= 1e-9


@pytest.mark.slow
@pytest.mark.parametrize("name", ["reciprocating_cam", "geneva", "optical_filter"])
def test_zone_containment_all_models_default(models, name):
    """Issue acceptance: 1000 seeded box vectors (a quarter corners) per model, every
    band of the operating channel of every pair, default preset."""
    m = models[name]
    ref = reference(m, "default")
    U = _random_box(m, 1000, 11)
    for pi, cs in enumerate(ref.spaces):
        z = contact_zones(cs, m, pi, "default", faces=[ref.faces[pi]])
        assert _excess(m, cs, z.bands, U, pi) <= 1e-9, cs.pair.name


def test_zones_of_the_operating_region_only(models):
    """With the cells the nominal motion passes through, only the curves bounding
    them get zones; the rest of the operating face is counted as skipped."""
    m = models["geneva"]
    ref = reference(m, "fast")
    cs, sim = ref.spaces[0], ref.sims[0]
    face = contact_zones(cs, m, 0, "fast", faces=[ref.faces[0]])
    region = contact_zones(cs, m, 0, "fast", faces=[ref.faces[0]], cells=sim.cells)
    bounding = {b for k, j in sim.cells
                for b in (cs.cells[k][j].lower, cs.cells[k][j].upper)} - {-1}
    assert {b.curve for b in region.bands} == bounding
    assert bounding < {b.curve for b in face.bands}
    assert region.stats["zones_skipped"] > face.stats["zones_skipped"]
    # a band does not depend on which other bands are computed
    by_curve = {b.curve: b for b in face.bands}
    for b in region.bands:
        np.testing.assert_array_equal(b.upper, by_curve[b.curve].upper)
        np.testing.assert_array_equal(b.lower, by_curve[b.curve].lower)


def _geneva_end_curves(m, preset):
    ref = reference(m, preset)
    cs = ref.spaces[0]
    return cs, [i for i, c in enumerate(cs.curves) if (c.label, c.branch) in GENEVA_END_CURVES]


@pytest.mark.parametrize("bracketed", [False, True])
def test_stacked_evaluation_equals_one_at_a_time(models, bracketed):
    """_Evaluator.many gives, per vector, the displacements and contact margins of
    a call with that vector alone (to rounding), in the Newton and the bracketed
    search; a vector that does not build gets NaN and no margin."""
    m = models["geneva"]
    cs, pick = _geneva_end_curves(m, "fast")
    bands = contact_zones(cs, m, 0, "fast", curves=pick).bands

    def build(u):
        try:
            with trusted():
                return m.build(u)
        except (ValueError, ArithmeticError):
            return None

    bad = m.nominal.copy()
    bad[m.names.index("pin_r")] = -1.0
    U = list(_random_box(m, 12, 4)) + [bad]
    assert build(bad) is None
    for b in bands:
        ev = _band_evaluator(cs, b, build)
        ev.nominal = build(m.nominal)
        if not bracketed:
            ev.bound = None
        got = ev.many(U)
        # the vector that does not build is left to the single call, counted
        assert ev.counts == {"stacked": len(U) - 1, "stack_fallbacks": 1}
        for u, (tau, v, mg) in zip(U, got):
            ev.last_margin = None
            t1, v1 = ev(u)
            np.testing.assert_allclose(tau, t1, rtol=0, atol=1e-12, equal_nan=True)
            np.testing.assert_allclose(v, v1, rtol=0, atol=1e-12, equal_nan=True)
            if ev.last_margin is None:
                assert mg is None
            else:
                np.testing.assert_allclose(mg, ev.last_margin, rtol=0, atol=1e-12)
        assert np.isnan(got[-1][0]).all() and got[-1][2] is None
        # a vector that does not build has no margin, not the last vector's
        ev(U[0])
        assert ev.last_margin is not None
        ev(bad)
        assert ev.last_margin is None


def test_zones_computed_ahead_are_those_of_one_vector_at_a_time(models, monkeypatch):
    """The stages evaluate their vectors in stacked passes ahead of asking for
    them; the bands, their extreme vectors and the count of vectors evaluated
    are those of asking one vector at a time (default preset: the corner
    searches, climbs and refinements near the Geneva curve ends)."""
    from cspace import zones
    m = models["geneva"]
    cs, pick = _geneva_end_curves(m, "default")
    stacked = []
    many = zones._Evaluator.many
    monkeypatch.setattr(zones._Evaluator, "many",
                        lambda self, us: stacked.append(len(us)) or many(self, us))
    za = contact_zones(cs, m, 0, "default", curves=pick)
    ahead = za.bands
    assert len(stacked) > 10 and sum(stacked) > 100
    # every value computed ahead is counted (stacked, or left to the single call)
    assert za.stats["stacked"] + za.stats["stack_fallbacks"] == sum(stacked)
    monkeypatch.setattr(zones._CurveZone, "prefetch", lambda self, us: None)
    single = contact_zones(cs, m, 0, "default", curves=pick).bands
    assert len(ahead) == len(single) >= 3
    for a, b in zip(ahead, single):
        assert a.n_evaluated == b.n_evaluated
        np.testing.assert_array_equal(a.u_upper, b.u_upper)
        np.testing.assert_array_equal(a.u_lower, b.u_lower)
        for f in ("upper", "lower", "vertical_upper", "vertical_lower"):
            np.testing.assert_allclose(getattr(a, f), getattr(b, f), rtol=0, atol=1e-12,
                                       equal_nan=True)


def test_zones_on_an_executor_are_the_serial_zones(recip_zones):
    """The curves' zones in tasks of an executor (here threads; synthesis uses
    its process pool): the same bands, overlaps and counts, in the same order;
    the builds counted once over all tasks; a failing task's error reaches
    the caller."""
    from concurrent.futures import ThreadPoolExecutor
    from unittest import mock

    import cspace.zones as zmod
    m, ref, serial = recip_zones
    with ThreadPoolExecutor(2) as ex:
        par = contact_zones(ref.spaces[0], m, 0, faces=[ref.faces[0]], executor=ex)
    assert len(serial.bands) >= 2
    assert [b.curve for b in par.bands] == [b.curve for b in serial.bands]
    for a, b in zip(par.bands, serial.bands):
        assert a.to_dict() == b.to_dict()
    assert [o.to_dict() for o in par.overlaps] == [o.to_dict() for o in serial.overlaps]
    assert par.stats == serial.stats
    from cspace.errors import InputError
    with pytest.raises(InputError, match="executor must be a concurrent.futures.Executor"):
        contact_zones(ref.spaces[0], m, 0, faces=[ref.faces[0]], executor="process")
    with mock.patch.object(zmod, "_zone_of_curve", side_effect=ValueError("boom")):
        with ThreadPoolExecutor(2) as ex, pytest.raises(ValueError, match="boom"):
            contact_zones(ref.spaces[0], m, 0, faces=[ref.faces[0]], executor=ex)
    # a pool whose workers stopped: a typed error that says the likely cause
    from cspace.errors import WorkerError
    with pytest.raises(WorkerError, match=r"if __name__ == \"__main__\":"):
        contact_zones(ref.spaces[0], m, 0, faces=[ref.faces[0]], executor=_BrokenPool())


class _BrokenPool(concurrent.futures.ThreadPoolExecutor):
    """An executor whose every task ends as a stopped worker's does."""

    def submit(self, fn, *args, **kwargs):
        from concurrent.futures import Future
        from concurrent.futures.process import BrokenProcessPool
        f = Future()
        f.set_exception(BrokenProcessPool("a process in the pool was terminated abruptly"))
        return f


def test_an_overlap_along_the_whole_drive_is_reported_to_its_ends():
    """A pin that may be wider than its slot (the Scotch yoke of
    ``batch/yoke.py``: a channel of one width all along the motion): the
    zone overlap spans the whole drive, to its ends, not only the band
    samples inside them."""
    from synthesis.loop import operating_zones

    from .batch.yoke import yoke
    m = yoke()
    ref = reference(m, "fast")
    (z,) = operating_zones(m, ref, "fast")
    (o,) = z.overlaps
    assert o.q1_range == pytest.approx(ref.drive, abs=1e-6)
