"""The defect test on a Scotch yoke whose channel and motion have closed forms
(``batch/yoke.py``): a pin of radius r between faces 2 w apart, the crank R."""

import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest

from cspace.defects import (DefectResult, Reason, assembled_start, check_deviation,
                            default_deviation, is_defective, reference)
from cspace.errors import CSpaceError, InputError, InvalidModelError, JammedNominalError
from cspace.freespace import Status, StartChoice, configuration_space
from cspace.match import ChangeKind
from cspace.simulate import SimStatus

from .batch.yoke import output, yoke

L = 25.0      # the yoke's characteristic length: the pin's reach R + r


@pytest.fixture(scope="module")
def yoke_ref():
    m = yoke()
    return m, reference(m, "fast")


def _cs(m, u):
    return configuration_space(m.build(u), "fast", window=m.window, deps=m.dependencies()[0])


# ------------------------------------------------------------------ reference
def test_reference_holds_the_nominal_motion(yoke_ref):
    m, ref = yoke_ref
    assert ref.spaces[0].pair.char_length == pytest.approx(L)
    assert ref.drive == (0.0, 2 * math.pi) and ref.starts == ((0.0, 20.0),)
    assert ref.faces[0] >= 0 and ref.spaces[0].faces[ref.faces[0]]
    assert ref.start_choices == (None,)          # the model states its start
    np.testing.assert_array_equal(ref.nominal, m.nominal)
    sim = ref.sims[0]
    assert sim.status == SimStatus.OK
    np.testing.assert_allclose(sim.q2, output(m.nominal, sim.q1), atol=1e-9)
    # no deviation stated: five times the largest tolerance at the reach L
    assert ref.d == pytest.approx(5 * 0.02 / L)


def test_reference_threshold_from_the_model_or_the_caller():
    m = yoke(deviation=0.25)
    assert reference(m, "fast").d == 0.25
    assert reference(m, "fast", d=0.125).d == 0.125
    with pytest.raises(InputError, match="deviation threshold d must be a finite number > 0"):
        reference(m, "fast", d=-1.0)


def test_reference_chooses_a_start_when_the_model_states_none():
    m = dataclasses.replace(yoke(), q2_start=None)
    ref = reference(m, "fast")
    (choice,) = ref.start_choices
    assert isinstance(choice, StartChoice)
    assert ref.starts[0] == (0.0, choice.q2)
    assert ref.spaces[0].classify(np.array([ref.starts[0]]))[0] != Status.BLOCKED


def test_a_default_start_from_which_the_motion_jams_gives_way():
    """With no stated start, the widest free interval at the drive's start is
    the pin's outside of the yoke (the motion jams against the window's
    edge); the reference takes the widest from which it completes the drive
    (the slot), and says so."""
    m = dataclasses.replace(yoke(), q2_start=None)
    ref = reference(m, "fast")
    (ch,) = ref.start_choices
    assert ref.sims[0].status == SimStatus.OK
    assert ch.intervals[ch.chosen] == pytest.approx((19.97, 20.03))
    assert ch.q2 == pytest.approx(20.0) and len(ch.jams) == 1
    assert "in which the nominal motion completes its drive (it jams from the middle of the " \
           "wider [-30, 4.97])" in ch.describe("mm")
    assert ch.to_dict()["jams"] == list(ch.jams)


def test_a_nominal_that_jams_is_refused():
    """A stated start from which the nominal motion jams (the pin outside the
    yoke meets the window's edge): no reference, with where it jams, the
    window edge named, and the motions for a caller that draws them."""
    m = dataclasses.replace(yoke(), q2_start=(-12.5,))
    with pytest.raises(JammedNominalError, match=r"the nominal design's motion jams") as e:
        reference(m, "fast")
    msg = str(e.value)
    assert "driver blocked at q1 = " in msg and "lower edge of the C-space window (q2 = -30)" in msg
    assert isinstance(e.value, InvalidModelError) and isinstance(e.value, ValueError)
    assert e.value.sims[0].status == SimStatus.JAMMED
    with pytest.raises(JammedNominalError):
        is_defective(m, m.nominal)
    # kept where asked (the synthesis loop's shifted design)
    assert reference(m, "fast", allow_jam=True).sims[0].status == SimStatus.JAMMED


def test_a_start_blocked_at_nominal_is_refused():
    # slid 7.5 left of the channel, the right bar sits on the pin
    m = dataclasses.replace(yoke(), q2_start=(12.5,))
    with pytest.raises(CSpaceError, match=r"start configuration \(q1, q2\) = \(0, 12\.5\) of "
                                          r"pair 'yoke' is blocked") as e:
        reference(m, "fast")
    # what is allowed: the free follower positions there, in the follower's unit
    cs = reference(yoke(), "fast").spaces[0]
    free = ", ".join(f"[{lo:.6g}, {hi:.6g}]" for lo, hi, _ in cs.free_intervals(0.0))
    assert f"free q2 at q1 = 0: {free} (mm)" in str(e.value)
    assert "[19.97, 20.03]" in free


def test_a_start_outside_the_window_is_named_so():
    m = dataclasses.replace(yoke(), q2_start=(-31.0,))       # window q2 in [-30, 30]
    with pytest.raises(CSpaceError, match=r"outside the follower window \[-30, 30\]; "
                                          r"q2_start must be a free follower position"):
        reference(m, "fast")


def test_a_preset_name_in_the_place_of_d_says_where_it_goes(yoke_ref):
    m, ref = yoke_ref
    with pytest.raises(InputError, match=r"got 'fast' \(the name of an accuracy preset: pass "
                                         r"it as accuracy='fast'\)"):
        is_defective(m, m.nominal, "fast")


def test_a_start_per_pair_must_match_the_pairs():
    m = dataclasses.replace(yoke(), q2_start=(0.0, 1.0))
    with pytest.raises(InputError, match=r"q2_start must give one follower start per pair "
                                         r"\(1\) or one for all, got 2: \[0\.0, 1\.0\]"):
        reference(m, "fast")


# ------------------------------------------------------------------ verdicts
def test_nominal_is_healthy(yoke_ref):
    m, ref = yoke_ref
    r = is_defective(m, None, ref=ref)
    assert not r.defective and r.reasons == () and r.where is None
    # a result reads as its verdict: `if is_defective(m, u):`
    assert not r and bool(DefectResult(True, (Reason.JAM,), 0.0, 0.1, None))
    assert r.max_deviation == 0.0 and r.d == ref.d and r.message == "healthy"
    assert r.sims == (SimStatus.OK,) and r.matches[0].same
    assert repr(r).startswith("<DefectResult: healthy")


def test_deviation_is_the_closed_form_motion(yoke_ref):
    """A crank 0.02 longer moves the follower by 0.02 cos q1 where it is pushed
    and by 0.02 at its rest: the largest deviation, over L, at the nominal's
    samples."""
    m, ref = yoke_ref
    u = m.nominal + np.array([0.02, 0.0, 0.0])
    x = ref.sims[0].q1
    want = np.max(np.abs(output(u, x) - output(m.nominal, x))) / L
    assert want == pytest.approx(0.02 / L, rel=1e-9)
    loose = is_defective(m, u, ref=ref)
    assert not loose.defective and loose.max_deviation == pytest.approx(want, abs=1e-12)
    tight = is_defective(m, u, d=1e-4, ref=ref)
    assert tight.defective and tight.reasons == (Reason.DEVIATION,)
    assert tight.d == 1e-4 and tight.max_deviation == pytest.approx(want, abs=1e-12)
    pair, q1, q2 = tight.where
    assert pair == 0
    # where: the variant's output at the driver position of the largest deviation
    assert abs(output(u, q1) - output(m.nominal, q1)) / L == pytest.approx(want, abs=1e-12)
    assert q2 == pytest.approx(float(output(u, q1)), abs=1e-9)
    assert "output deviates by" in tight.message and repr(tight).startswith(
        "<DefectResult: DEFECTIVE - ")


def test_a_pin_wider_than_its_slot_jams_and_closes_the_channel(yoke_ref):
    m, ref = yoke_ref
    r = is_defective(m, {"pin_r": 5.04}, ref=ref)
    assert r.defective and r.reasons == (Reason.TOPOLOGY, Reason.JAM)
    assert r.where == (0, 0.0, 20.0)
    assert r.sims == (SimStatus.START_BLOCKED,)
    assert r.matches[0].changes[0].kind == ChangeKind.CHANNEL_CLOSED
    # the same vector given in full
    same = is_defective(m, [20.0, 5.04, 5.03], ref=ref)
    assert same.reasons == r.reasons and same.message == r.message


def test_an_unbuildable_variant_is_invalid(yoke_ref):
    m, ref = yoke_ref
    r = is_defective(m, {"pin_r": -1.0}, ref=ref)
    assert r.defective and r.reasons == (Reason.INVALID,)
    assert r.max_deviation == math.inf and r.where is None
    assert r.message.startswith("invalid geometry:") and "radius" in r.message


@pytest.mark.parametrize("u, d, reason", [([20.0, 5.04, 5.03], 1e-4, Reason.JAM),
                                          ([20.02, 5.0, 5.03], 1e-4, Reason.DEVIATION),
                                          ([20.01, 5.01, 5.03], 1e-3, None)])
def test_stop_early_gives_the_same_verdict(yoke_ref, u, d, reason):
    m, ref = yoke_ref
    full = is_defective(m, u, d=d, ref=ref)
    early = is_defective(m, u, d=d, ref=ref, stop_early=True)
    assert early.defective == full.defective
    if reason is None:
        assert not early.defective and early.max_deviation == full.max_deviation
    else:
        # the first defect found, and only that
        assert early.reasons == (reason,) and reason in full.reasons


@pytest.mark.parametrize("first", [1, -1, 0.0, "0"])
def test_first_pair_must_be_a_pair_index(yoke_ref, first):
    m, ref = yoke_ref
    with pytest.raises(InputError, match=r"first_pair must be a pair index in \[0, 0\]"):
        is_defective(m, None, ref=ref, stop_early=True, first_pair=first)


# ------------------------------------------------------------------ assembled start
def test_a_variant_is_assembled_at_the_near_end_of_its_moved_channel(yoke_ref):
    """A crank 0.05 shorter puts the channel at q1 = 0 at [19.92, 19.98]: the
    stated start 20 is blocked, the follower is assembled a hair inside the
    channel's top."""
    m, ref = yoke_ref
    cs = _cs(m, [19.95, 5.0, 5.03])
    assert cs.classify(np.array([[0.0, 20.0]]))[0] == Status.BLOCKED
    q2 = assembled_start(ref.spaces[0], cs, ref.starts[0])
    assert q2 == pytest.approx(19.98, abs=1e-7) and q2 < 19.98
    assert cs.classify(np.array([[0.0, q2]]))[0] != Status.BLOCKED


def test_a_start_free_in_the_variant_stays_and_a_closed_channel_gives_it_back(yoke_ref):
    m, ref = yoke_ref
    assert assembled_start(ref.spaces[0], _cs(m, [19.99, 5.0, 5.03]), (0.0, 20.0)) == 20.0
    # no free interval of the variant overlaps the nominal channel: the stated value
    assert assembled_start(ref.spaces[0], _cs(m, [20.0, 5.04, 5.03]), (0.0, 20.0)) == 20.0


# ------------------------------------------------------------------ thresholds
@pytest.mark.parametrize("good, want", [(0.1, 0.1), (2, 2.0), (np.float64(1e-6), 1e-6)])
def test_check_deviation_accepts_positive_numbers(good, want):
    assert check_deviation(good) == want


@pytest.mark.parametrize("bad", [0, -0.5, float("nan"), float("inf"), True, None, "abc", "0.5",
                                 [0.1]])
def test_check_deviation_refuses_other_values(bad):
    with pytest.raises(InputError, match="deviation threshold d must be a finite number > 0") \
            as e:
        check_deviation(bad)
    assert e.value.name == "d"


def test_default_deviation_is_five_tolerances_at_the_shortest_reach():
    spaces = [SimpleNamespace(pair=SimpleNamespace(char_length=L)) for L in (40.0, 8.0)]
    model = SimpleNamespace(tol=np.array([0.01, 0.04, 0.02]))
    assert default_deviation(model, spaces) == pytest.approx(5 * 0.04 / 8.0)
    # without tolerances there is no scale: a fixed 1e-3
    assert default_deviation(SimpleNamespace(tol=np.zeros(3)), spaces) == 1e-3
    assert default_deviation(SimpleNamespace(tol=np.zeros(0)), spaces) == 1e-3


def test_an_angle_tolerance_counts_as_the_arc_it_turns_through():
    """An angle's tolerance (rad) was compared with the lengths' as it is: a
    rocker arm's 0.1 deg gave d = 0.0044 rad drawn in inches (0.0017 'in'
    beat the 0.001 in lengths) and 0.0025 rad in millimetres.  It counts as
    tol * L: d is 5 times it in rad, in either unit."""
    deg = np.radians(0.1)

    def model(scale):
        ps = [SimpleNamespace(unit=""), SimpleNamespace(unit=""), SimpleNamespace(unit="rad")]
        return SimpleNamespace(tol=np.array([0.001 * scale, 0.0005 * scale, deg]),
                               names=("a", "b", "arm"), parameters=ps)

    for scale in (1.0, 25.4):
        spaces = [SimpleNamespace(pair=SimpleNamespace(char_length=2.0 * scale))]
        assert default_deviation(model(scale), spaces) == pytest.approx(5 * deg)
    # an angle tolerance smaller than the lengths' in effect: the lengths decide
    spaces = [SimpleNamespace(pair=SimpleNamespace(char_length=0.5))]
    assert default_deviation(model(1.0), spaces) == pytest.approx(5 * 0.001 / 0.5)


# ------------------------------------------------------------------ results as JSON
def test_defect_result_round_trip_through_a_dict():
    r = DefectResult(True, (Reason.JAM, Reason.DEVIATION), 0.25, 0.1, (0, 1.5, float("nan")),
                     (), (SimStatus.JAMMED,), "jam")
    d = r.to_dict()
    assert d["where"] == [0, 1.5, None] and d["reasons"] == [Reason.JAM.value,
                                                              Reason.DEVIATION.value]
    back = DefectResult.from_dict(d)
    assert back.defective and back.reasons == r.reasons and back.sims == r.sims
    assert back.where[:2] == (0, 1.5) and math.isnan(back.where[2])
    assert back.max_deviation == 0.25 and back.d == 0.1 and back.message == "jam"
    assert back.to_dict() == d
    # an unbounded deviation (an invalid variant) is written as null and read back
    inv = DefectResult(True, (Reason.INVALID,), math.inf, 0.1, None, (), (), "invalid")
    assert inv.to_dict()["max_deviation"] is None
    assert DefectResult.from_dict(inv.to_dict()).max_deviation == math.inf


def test_defect_result_from_dict_refuses_other_documents():
    good = DefectResult(False, (), 0.01, 0.1, None).to_dict()
    with pytest.raises(TypeError, match="JSON object"):
        DefectResult.from_dict([good])
    with pytest.raises(ValueError, match=r"where must be \[pair, q1, q2\]"):
        DefectResult.from_dict(dict(good, where=[0, 1.0]))
    with pytest.raises(TypeError, match="expected true or false"):
        DefectResult.from_dict(dict(good, defective=1))
    with pytest.raises(ValueError):
        DefectResult.from_dict(dict(good, reasons=["no such reason"]))
    with pytest.raises(KeyError):
        DefectResult.from_dict({k: v for k, v in good.items() if k != "d"})


def test_a_blocked_start_names_the_contacts_around_it():
    """A pin wider than its slot: the start is blocked between the pin's two
    contacts with the slot's faces, and the message says so, and that no
    follower position fits there."""
    from cspace.errors import CSpaceError

    from .batch.yoke import yoke
    m = yoke(w=4.9)                            # half width below the pin radius 5
    with pytest.raises(CSpaceError) as e:
        reference(m, "fast")
    msg = str(e.value)
    assert "is blocked (the parts overlap there, between the contacts" in msg
    assert "crank:pin|yoke:" in msg and "(below)" in msg and "(above)" in msg


def test_main_reason_is_the_jam_when_the_drive_jams():
    r = DefectResult(True, (Reason.TOPOLOGY, Reason.JAM), 0.0, 0.1, (0, 1.0, 0.0))
    assert r.main_reason is Reason.JAM
    assert DefectResult(True, (Reason.DEVIATION,), 0.2, 0.1, None).main_reason is Reason.DEVIATION
    assert DefectResult(False, (), 0.0, 0.1, None).main_reason is None
