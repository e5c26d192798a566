"""Force-closed (spring-loaded) followers: ``Pair.bias``, its file forms, and the
simulation, defect test and batched margins of such pairs.

The closed forms come from the Scotch yoke of ``batch/yoke.py``: a pin of
radius r on a crank of radius R between two faces a distance 2 w apart, the
follower sliding along x.  Its channel at driver angle q1 is

    R cos q1 - c  <=  s  <=  R cos q1 + c,      c = w - r,

so a follower held toward decreasing s rests at ``R cos q1 - c`` at every q1,
one held toward increasing s at ``R cos q1 + c``.  A variant (R', c') of a
held-down follower moves by ``(R' - R) cos q1 - (c' - c)``: its largest
deviation over a turn is ``|R' - R| + |c' - c|`` (at q1 = 0 or pi).
"""

import dataclasses
import json
import math

import numpy as np
import pytest

from cspace.batch.margins import defect_margins, plans_of
from cspace.defects import Reason, is_defective, reference
from cspace.errors import FileFormatError, InputError
from cspace.freespace import configuration_space
from cspace.geom2d import TWO_PI
from cspace.geometry import Assembly, Pair
from cspace.io import load_pair, pair_from_dict, save_pair
from cspace.simulate import SimStatus, simulate
from mechanisms.dimensions import parametric_model
from mechanisms.userfile import model_from_dict, model_to_dict

from .batch.yoke import build_yoke, output, yoke


def _held_down_yoke(v):
    return dataclasses.replace(build_yoke(v), bias=-1)


def _held_up_filters(v):
    from mechanisms.models.optical import build_optical
    out = build_optical(v)
    return Assembly(tuple(dataclasses.replace(p, bias=1) for p in out.pairs), out.name)


def _yoke_values(m, u=None):
    v = m.values(u)
    return v["crank"], v["half_width"] - v["pin_r"]


# ------------------------------------------------------------------ the value

@pytest.mark.parametrize("bad", [True, 2, 0.5, -1.5, "-1", None, math.nan])
def test_a_bias_other_than_minus_one_zero_or_one_is_refused(bad):
    pair = build_yoke({"crank": 20.0, "pin_r": 5.0, "half_width": 5.03})
    with pytest.raises(InputError, match=r"Pair\.bias must be -1 .* 0 .* or \+1 .*got") as e:
        dataclasses.replace(pair, bias=bad)
    assert e.value.name == "Pair.bias"


def test_form_closure_is_the_default_and_files_without_closure_are_unchanged(tmp_path):
    pair = build_yoke({"crank": 20.0, "pin_r": 5.0, "half_width": 5.03})
    assert pair.bias == 0
    assert "closure" not in pair.to_dict()
    held = dataclasses.replace(pair, bias=1.0)
    assert held.bias == 1 and isinstance(held.bias, int) and held != pair
    assert held.to_dict()["closure"] == {"bias": 1}
    save_pair(held, tmp_path / "p.json", {"q2_start": [20.0]})
    back = load_pair(tmp_path / "p.json")
    assert back == held and back.bias == 1
    # an assembly keeps each pair's own closure
    other = dataclasses.replace(pair, name="other")
    asm = Assembly((held, other), name="two")
    save_pair(asm, tmp_path / "a.json")
    assert [p.bias for p in load_pair(tmp_path / "a.json").pairs] == [1, 0]


@pytest.mark.parametrize("closure, where, what", [
    ({"bias": 0.5}, "closure.bias", "got float 0.5"),
    ({"bias": True}, "closure.bias", "got bool True"),
    ({"bias": "-1"}, "closure.bias", "got str '-1'"),
    ({"bias": 2}, "closure.bias", "got int 2"),
    ({}, "closure", "missing required key 'bias'"),
    ({"bias": -1, "spring": 3}, "closure", r"unknown keys \['spring'\]"),
    (-1, "closure", "expected an object"),
])
def test_a_bad_closure_in_a_pair_file_names_its_path(closure, where, what):
    d = build_yoke({"crank": 20.0, "pin_r": 5.0, "half_width": 5.03}).to_dict()
    with pytest.raises(FileFormatError, match=what) as e:
        pair_from_dict(dict(d, closure=closure))
    assert e.value.path == where
    if "bias" in where:
        assert "expected -1" in str(e.value) and "or 1" in str(e.value)
    # inside an assembly the path names the pair
    asm = {"format": "cspace-assembly", "version": 1, "name": "a",
           "pairs": [d, dict(d, name="second", closure=closure)]}
    with pytest.raises(FileFormatError) as e:
        pair_from_dict(asm)
    assert e.value.path == f"pairs[1].{where}"


def _doc(closure=None):
    pair = {"name": "cam", "parts": [
        {"name": "cam", "axis": {"type": "rotation", "center": [0, 0]},
         "loops": [[{"type": "arc", "center": [0, "-ecc"], "radius": "r", "start_angle": 0,
                     "end_angle": "2*pi"}]]},
        {"name": "follower", "axis": {"type": "translation", "direction": [0, 1]},
         "loops": [{"polyline": [[-4, "r"], [4, "r"], [4, "r + 1"], [-4, "r + 1"]]}]}]}
    if closure is not None:
        pair["closure"] = closure
    return {"format": "cspace-model", "version": 1, "name": "disc", "units": "mm",
            "parameters": [{"name": "r", "nominal": 10.0, "tol": 0.01},
                           {"name": "ecc", "nominal": 2.0, "tol": 0.01}],
            "window": [0, "2*pi", -6, 6], "q2_start": [1.0], "pairs": [pair]}


def test_a_model_file_states_the_closure_per_pair():
    d = _doc({"bias": -1})
    m = model_from_dict(d)
    assert m.build().bias == -1 and m.build(m.nominal + m.tol).bias == -1
    assert model_to_dict(m) == d
    assert model_from_dict(_doc()).build().bias == 0
    with pytest.raises(FileFormatError, match="expected -1") as e:
        model_from_dict(_doc({"bias": -2}))
    assert e.value.path == "pairs[0].closure.bias"
    # every dimension a parameter: the pair keeps its closure
    pm = parametric_model(m.build(), 0.01)
    assert pm.build().bias == -1
    assert json.loads(json.dumps(model_to_dict(pm)))["pairs"][0]["closure"] == {"bias": -1}


# ------------------------------------------------------------------ simulation

@pytest.fixture(scope="module")
def yoke_space():
    m = yoke()
    return m, configuration_space(m.build(), "fast", window=m.window)


@pytest.mark.parametrize("bias", [-1, 1])
def test_a_held_yoke_rides_the_bound_of_its_channel(yoke_space, bias):
    m, cs = yoke_space
    R, c = _yoke_values(m)
    r = simulate(cs, 0.0, 2 * math.pi, 20.0, bias=bias)
    assert r.status == SimStatus.OK and r.bias == bias
    np.testing.assert_allclose(r.q2, R * np.cos(r.q1) + bias * c, rtol=0, atol=1e-9)
    # held toward -x, the yoke's right face rests on the pin; toward +x, its left
    face = "r.face" if bias < 0 else "l.face"
    assert all(face in lab for lab in r.contact)
    # the pair's own closure is the default; the argument overrides it
    held = configuration_space(dataclasses.replace(cs.pair, bias=bias), "fast",
                               window=m.window)
    again = simulate(held, 0.0, 2 * math.pi, 20.0)
    np.testing.assert_array_equal(again.q2, r.q2)
    free = simulate(held, 0.0, 2 * math.pi, 20.0, bias=0)
    np.testing.assert_allclose(free.q2, output(m.nominal, free.q1), rtol=0, atol=1e-9)


def test_form_closure_is_the_default_motion(yoke_space):
    m, cs = yoke_space
    r = simulate(cs, 0.0, 2 * math.pi, 20.0)
    assert r.bias == 0
    np.testing.assert_allclose(r.q2, output(m.nominal, r.q1), rtol=0, atol=1e-9)
    with pytest.raises(InputError, match="bias must be -1"):
        simulate(cs, 0.0, 1.0, 20.0, bias=3)


def test_the_start_picks_the_channel_and_must_be_free(yoke_space):
    m, cs = yoke_space
    R, c = _yoke_values(m)
    # anywhere in the channel: laid on its lower bound at once
    for s0 in (R - 0.5 * c, R, R + c):
        r = simulate(cs, 0.0, 0.5, s0, bias=-1)
        assert r.q2[0] == pytest.approx(R - c, abs=1e-12)
    # outside the channel the start is blocked, as for form closure
    r = simulate(cs, 0.0, 0.5, R + 3 * c, bias=-1)
    assert r.status == SimStatus.START_BLOCKED


def _bound_distance(cs, q1, q2, bias):
    """Distance of q2 from the nearest bias-side end of a free interval at q1."""
    ends = [iv[0] if bias < 0 else iv[1] for iv in cs.free_intervals(q1)]
    if cs.periodic[1]:
        return min(abs((q2 - e + math.pi) % TWO_PI - math.pi) for e in ends)
    return min(abs(q2 - e) for e in ends)


@pytest.mark.parametrize("name, bias", [("reciprocating_cam", -1), ("reciprocating_cam", 1),
                                        ("geneva", 1)])
def test_a_held_follower_rests_on_a_free_interval_end(models, name, bias):
    """At every sample the follower lies at the bias-side end of a free interval
    (:meth:`ConfigurationSpace.free_intervals`, computed apart from the
    simulation), sliding or rotating, over one driver turn."""
    m = models[name]
    cs = configuration_space(m.build(), "fast", window=m.window)
    r = simulate(cs, 0.0, 2 * math.pi, m.q2_start[0], bias=bias)
    assert r.status == SimStatus.OK
    assert np.ptp(r.q2) > 0.1
    for i in range(0, len(r.q1), 5):
        assert _bound_distance(cs, r.q1[i], r.q2[i], bias) < 1e-7, (r.q1[i], r.q2[i])
    # continuous output: no turn lost or gained between samples
    assert np.max(np.abs(np.diff(r.q2))) < 0.5


def test_a_wheel_sprung_the_way_it_indexes_snaps_into_the_relief_and_jams(models):
    """A Geneva wheel held toward decreasing q2, the way it indexes, leaves the
    lock as soon as the relief lets it, springs ahead into the free pocket
    where a wheel tip sits in the relief, and rests there until the pocket
    closes on it: the drive jams.  The jam lies where the follower's free
    interval narrows to nothing."""
    m = models["geneva"]
    cs = configuration_space(m.build(), "fast", window=m.window)
    r = simulate(cs, 0.0, m.drive[1], 0.0, bias=-1)
    assert r.status == SimStatus.JAMMED
    x, q = r.jam_q
    assert 0.0 < x < 2 * math.pi

    def holding(q1):
        return [b - a for a, b, _ in cs.free_intervals(q1)
                if a - 1e-4 <= q <= b + 1e-4]
    before = holding(x - 1e-5)
    assert len(before) == 1 and before[0] < 1e-3
    assert holding(x + 1e-5) == []
    # form-closed, the same wheel indexes through the whole drive
    assert simulate(cs, 0.0, m.drive[1], 0.0).status == SimStatus.OK


def test_a_rotating_follower_with_a_free_turn_keeps_its_place():
    """Nothing bounds a rotating follower that the driver never reaches: held
    or not, it stays where it starts."""
    from cspace.geometry import Arc, Loop, Part, Rotation
    disc = Part("disc", (Loop((Arc((0.0, 0.0), 1.0, 0.0, 2 * math.pi, name="rim"),)),),
                Rotation((0.0, 0.0)))
    lever = Part("lever", (Loop.from_bulges([(9.0, -0.5), (12.0, -0.5), (12.0, 0.5),
                                             (9.0, 0.5)]),), Rotation((10.0, 0.0)))
    cs = configuration_space(Pair(disc, lever, "mm", "apart", bias=-1), "fast")
    r = simulate(cs, 0.0, 2 * math.pi, 0.3)
    assert r.status == SimStatus.OK and np.all(r.q2 == 0.3) and set(r.contact) == {""}


# ------------------------------------------------------------------ defect test, margins

@pytest.fixture(scope="module")
def held_yoke():
    m = dataclasses.replace(yoke(deviation=0.001), builder=_held_down_yoke)
    return m, reference(m, "fast")


def test_the_defect_test_measures_a_held_follower_s_deviation(held_yoke):
    m, ref = held_yoke
    assert ref.sims[0].bias == -1
    x = ref.sims[0].q1

    def closed_form(dR, dc, L):
        # the largest |dR cos q1 - dc| over the nominal's samples (where the
        # test measures), near (|dR| + |dc|) / L
        return np.max(np.abs(dR * np.cos(x) - dc)) / L

    u = m.nominal + np.array([0.01, -0.005, 0.0])     # R up, c up
    r = is_defective(m, u, ref=ref)
    want = closed_form(0.01, 0.005, m.build().char_length)     # the nominal's metric
    assert r.max_deviation == pytest.approx(want, abs=1e-12)
    assert want < ref.d and not r.defective
    u = m.nominal + np.array([0.02, 0.0, 0.01])      # R up, c up more (the start stays free)
    r = is_defective(m, u, ref=ref)
    want = closed_form(0.02, 0.01, m.build().char_length)
    assert want > ref.d and r.defective and r.reasons == (Reason.DEVIATION,)
    assert r.max_deviation == pytest.approx(want, abs=1e-12)


def test_batched_verdicts_and_margins_of_a_held_follower(held_yoke):
    """Seeded box samples: the batch's verdicts equal the full test's, and its
    deviation margin is d minus the closed form (|dR| + |dc|) / L, with L the
    nominal's characteristic length (the metric of the design intent)."""
    from synthesis.verify import box_samples
    m, ref = held_yoke
    U = box_samples(m.nominal, m.tol, 60, seed=7)
    mb = defect_margins(m, U, ref, fallback=False)
    full = [is_defective(m, u, ref=ref) for u in U]
    cert = mb.certified
    assert cert.sum() >= 0.8 * len(U)
    assert 0 < sum(r.defective for r in full) < len(U)
    for v in np.nonzero(cert)[0]:
        assert mb.defective[v] == full[v].defective, (v, mb.results[v], full[v])
    done = defect_margins(m, U, ref)
    assert done.defective.tolist() == [r.defective for r in full]
    # where the channel stays open the motion is the closed form, measured at
    # the nominal's samples
    plan = plans_of(ref)[0]
    x = plan.x[plan.is_ref]
    dR = U[:, 0] - m.nominal[0]
    dc = (U[:, 2] - U[:, 1]) - (m.nominal[2] - m.nominal[1])
    open_ = (m.nominal[2] - m.nominal[1] + dc) > 1e-3
    dev = np.max(np.abs(dR[:, None] * np.cos(x)[None, :] - dc[:, None]), axis=1)
    np.testing.assert_allclose(mb.deviation[open_], ref.d - dev[open_] / plan.scale2,
                               rtol=0, atol=1e-12)


def test_batched_verdicts_where_a_held_follower_jumps(models):
    """Optical-filter followers held toward increasing q2 (against their swing)
    snap back where the pin leaves the slot: the output jumps at an event.
    The full test reads a variant there by interpolating between its own
    samples, which the bound at the nominal's event sample does not give; the
    batch leaves the variants whose verdict hangs on it to the full test, and
    every verdict it certifies is the full test's."""
    from synthesis.verify import box_samples
    m = dataclasses.replace(models["optical_filter"], builder=_held_up_filters)
    ref = reference(m, "fast")
    assert all(s.bias == 1 and np.max(np.abs(np.diff(s.q2))) > 0.05 for s in ref.sims)
    U = box_samples(m.nominal, m.tol, 12, seed=11)
    mb = defect_margins(m, U, ref, fallback=False)
    full = [is_defective(m, u, ref=ref).defective for u in U]
    for v in np.nonzero(mb.certified)[0]:
        assert mb.defective[v] == full[v], v
    assert defect_margins(m, U, ref).defective.tolist() == full
