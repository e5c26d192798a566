import math

import numpy as np
import pytest

from cspace.errors import InputError
from cspace.simulate import SimStatus, simulate, simulate_system

from ..conftest import brute_overlap


def test_geneva_indexes_by_exactly_a_quarter_turn(cspaces):
    cs = cspaces["geneva"][0]
    r = simulate(cs, 0.0, 6 * math.pi, 0.0)
    assert r.status == SimStatus.OK
    at = [r.output_at(k * 2 * math.pi) for k in range(4)]
    # from the first index on, every driver turn indexes the wheel by -pi/2 exactly
    np.testing.assert_allclose(np.diff(at[1:]), -math.pi / 2, atol=1e-6)
    # the first turn starts in the middle of the lock play, so it indexes to within it
    assert abs(at[1] - at[0] + math.pi / 2) < 0.05
    # dwell: the wheel does not move while locked (after the pin has left the slot)
    sel = (r.q1 > 4.2) & (r.q1 < 2 * math.pi + 2.0)
    assert np.ptp(r.q2[sel]) < 1e-12
    assert {lab for lab in r.contact if lab}.issuperset({"driver:pin|wheel:slot2.right"})


@pytest.mark.parametrize("name", ["geneva", "reciprocating_cam"])
@pytest.mark.parametrize("turns", [3, -3])
def test_every_turn_of_a_multi_turn_drive_passes_every_slab(cspaces, name, turns):
    """A periodic driver sweeps the whole window each turn, so the motion passes
    every slab once per turn, in order.  Regression: an event of a later turn
    wrapped back into the window a rounding error below itself, the slab ahead
    was not entered and the follower was clamped to the previous slab's curves."""
    cs = cspaces[name][0]
    q2 = cs.default_start(0.0)
    r = simulate(cs, 0.0, turns * 2 * math.pi, q2)
    assert r.status == SimStatus.OK
    nslab = len(cs.events) - 1
    slabs = [k for k, _ in r.cells]
    step = 1 if turns > 0 else -1
    assert all((b - a) % nslab == step % nslab for a, b in zip(slabs[:-1], slabs[1:]))
    assert len(slabs) == abs(turns) * nslab
    # every cell the motion passes through is free
    assert all(cs.cells[k][j].free for k, j in set(r.cells))


def _brute_free_interval(pair, t, s_in, lo=-1.0, hi=1.0, n=8001):
    """Free slide interval containing s_in at driver angle t: a shapely brute force."""
    s = np.linspace(lo, hi, n)
    free = ~brute_overlap(pair, np.stack([np.full_like(s, t), s], 1))
    i = int(np.argmin(np.abs(s - s_in)))
    assert free[i]
    a = i
    while a > 0 and free[a - 1]:
        a -= 1
    b = i
    while b < n - 1 and free[b + 1]:
        b += 1
    return s[a], s[b]


def test_reciprocating_cam_stroke_matches_brute_force(models, cspaces):
    """The yoke reciprocates between the cup extremes that its geometry gives."""
    cs = cspaces["reciprocating_cam"][0]
    r = simulate(cs, 0.0, 2 * math.pi, 0.45)
    assert r.status == SimStatus.OK
    pair = models["reciprocating_cam"].build()
    # the extremes of the motion: pushed to the cup tips; check each against the
    # free interval found by brute force at that driver angle
    late = np.nonzero(r.q1 > 1.2)[0]  # after the first push (the start is arbitrary)
    hi_i = late[int(np.argmax(r.q2[late]))]
    lo_i = late[int(np.argmin(r.q2[late]))]
    a, _ = _brute_free_interval(pair, r.q1[hi_i], r.q2[hi_i] + 1e-3)
    _, b = _brute_free_interval(pair, r.q1[lo_i], r.q2[lo_i] - 1e-3)
    assert r.q2[hi_i] == pytest.approx(a, abs=5e-4)  # pushed by the lower wall
    assert r.q2[lo_i] == pytest.approx(b, abs=5e-4)  # pushed by the upper wall
    assert 0.3 < r.q2[hi_i] - r.q2[lo_i] < 1.0
    # six strokes per turn: over one turn from q1 = 0 (mid-stroke) the direction of
    # motion reverses five times
    v = np.diff(r.q2)
    moving = v[np.abs(v) > 1e-9]
    assert np.count_nonzero(np.diff(np.sign(moving)) != 0) == 5


def test_optical_followers_turn_and_lock_in_staggered_windows(models, cspaces):
    m = models["optical_filter"]
    sys_ = simulate_system(cspaces["optical_filter"], m.drive[0], m.drive[1], m.q2_start)
    assert sys_.success
    for k, r in enumerate(sys_.results):
        centre = math.pi - k * math.pi / 2
        moving = np.abs(np.gradient(r.q2, r.q1)) > 1e-9
        assert r.q1[moving].min() > centre - math.pi / 4 - 0.05
        assert r.q1[moving].max() < centre + math.pi / 4 + 0.05
        assert r.q2[-1] - r.q2[0] == pytest.approx(-math.pi / 2, abs=0.05)
        locked_after = r.q1 > centre + math.pi / 4 + 0.05
        assert np.ptp(r.q2[locked_after]) < 1e-12


def test_reverse_drive_returns(cspaces):
    cs = cspaces["reciprocating_cam"][0]
    fwd = simulate(cs, 0.0, 1.0, 0.45)
    back = simulate(cs, 1.0, 0.0, fwd.q2[-1])
    assert back.status == SimStatus.OK and back.q1[-1] == 0.0
    assert np.all(np.diff(back.q1) < 0)


def test_output_at_only_inside_the_simulated_range(cspaces):
    from cspace.errors import NonFiniteError
    cs = cspaces["reciprocating_cam"][0]
    r = simulate(cs, 0.0, 2 * math.pi, 0.45)
    assert r.status == SimStatus.OK
    # inside, at both ends and a rounding error beyond them: the samples themselves
    np.testing.assert_array_equal(r.output_at(r.q1), r.q2)
    assert r.output_at(2 * math.pi * (1 + 1e-15)) == r.q2[-1]
    assert r.output_at(-1e-15) == r.q2[0]
    # outside: refused, naming the range (it used to return the last value)
    for bad in (10.0, -0.5, [1.0, 7.0, 9.0]):
        with pytest.raises(InputError, match=r"inside the simulated range \[0, 6.28319\]") as e:
            r.output_at(bad)
        assert e.value.name == "q1"
    with pytest.raises(InputError, match=r"got 2 values outside it, the farthest 9;"):
        r.output_at(np.array([1.0, 7.0, 9.0]))
    with pytest.raises(NonFiniteError, match="finite driver coordinates"):
        r.output_at([1.0, float("nan")])
    with pytest.raises(InputError, match="a number or an array of numbers"):
        r.output_at("half")
    # a reverse drive: the range is the same whichever way the driver ran
    fwd = simulate(cs, 0.0, 1.0, 0.45)
    back = simulate(cs, 1.0, 0.0, fwd.q2[-1])
    assert back.status == SimStatus.OK and back.q1[0] > back.q1[-1]
    assert min(back.q2) <= back.output_at(0.5) <= max(back.q2)
    with pytest.raises(InputError, match=r"\[0, 1\], got 1.5"):
        back.output_at(1.5)


def test_blocked_start_and_bad_input(cspaces):
    cs = cspaces["geneva"][0]
    r = simulate(cs, 0.0, 1.0, 1.0)  # (0, 1) is inside the wheel material
    assert r.status == SimStatus.START_BLOCKED and r.jam_q is not None
    with pytest.raises(InputError):
        simulate(cs, float("nan"), 1.0, 0.0)
    with pytest.raises(InputError, match="step"):
        simulate(cs, 0.0, 1.0, 0.0, step=-1.0)


def test_jam_is_reported_where_the_channel_closes(models):
    from mechanisms.analysis import model_cspaces
    m = models["geneva"]
    cs, = model_cspaces(m, {"pin_r": 0.45})  # the pin no longer fits the slots
    r = simulate(cs, 0.0, 2 * math.pi, 0.0)
    assert r.status == SimStatus.JAMMED
    assert 2.2 < r.jam_q[0] < 2.8  # where the pin meets the slot mouth
    assert r.q1[-1] == pytest.approx(r.jam_q[0])


@pytest.mark.parametrize("name", ["geneva", "reciprocating_cam"])
def test_batched_curve_values_do_not_change_the_motion(cspaces, monkeypatch, name):
    """The event rows are evaluated in one array call per curve before the walk
    (``_prefetch``); point by point on demand, the motion is the same bit for bit."""
    import cspace.simulate as sim
    cs = cspaces[name][0]
    q2 = cs.default_start(0.0)
    a = simulate(cs, 0.0, 4 * math.pi, q2)
    monkeypatch.setattr(sim, "_prefetch", lambda *args: None)
    b = simulate(cs, 0.0, 4 * math.pi, q2)
    assert np.array_equal(a.q1, b.q1) and np.array_equal(a.q2, b.q2)
    assert a.contact == b.contact and a.cells == b.cells


def test_first_reach_follows_the_clamp_rule():
    """The vectorised rest test finds the first sample where the sequential clamp
    (``_place_in``) would move a follower at rest, periodic or not, with
    unbounded and NaN bounds."""
    from cspace.simulate import _first_reach, _place_in
    rng = np.random.default_rng(3)
    for periodic in (False, True):
        for _ in range(300):
            n = int(rng.integers(1, 12))
            lo = rng.uniform(-4, 4, n)
            hi = lo + rng.uniform(0, 3, n)
            lo[rng.random(n) < 0.1] = -np.inf
            lo[rng.random(n) < 0.05] = np.nan
            hi[rng.random(n) < 0.05] = np.nan
            q2 = float(rng.uniform(-8, 8))
            moved = [_place_in(q2, a, b, periodic)[1] != 0 for a, b in zip(lo, hi)]
            want = moved.index(True) if any(moved) else n
            assert _first_reach(q2, lo, hi, periodic) == want


def test_a_drive_in_degrees_is_refused_with_the_hint():
    """A turning driver's drive of 90 rad or more (here (0, 360): 57 turns) is
    most likely written in degrees: refused, with the radians it meant."""
    from cspace.defects import reference
    from cspace.errors import InputError
    from mechanisms.models import geneva
    ref = reference(geneva(), "fast")
    with pytest.raises(InputError, match=r"turns the rotating driver 360 rad \(57.3 turns\).*"
                                         r"written in degrees\? radians\(0\) and radians\(360\) "
                                         r"are 0 and 6.28319 rad"):
        simulate(ref.spaces[0], 0.0, 360.0, ref.starts[0][1])
