"""Model-level analysis (``mechanisms.analysis``): resolving a model, the C-space
of every pair, the operating point a pair file states, the simulated motion
and the notes on the operating point."""

import dataclasses
import json
import math
from types import SimpleNamespace

import numpy as np
import pytest

from cspace.errors import CSpaceError, FileFormatError, InputError
from cspace.freespace import StartChoice
from cspace.geometry import Assembly, Pair
from cspace.io import pair_to_dict
from cspace.simulate import SimStatus, simulate
from mechanisms.analysis import (MOTION_KEYS, AmbiguousStartError, OperatingPointWarning,
                                 default_drive, follower_unit, model_cspaces, motion_at,
                                 operating_point_notes, pair_file_motion, pair_file_start,
                                 pairs_of, resolve_model, simulate_pairs)
from mechanisms.models import (BUILTIN, Model, eccentric_cam, geneva, optical_filter,
                               reciprocating_cam)

TWO_PI = 2 * math.pi


@pytest.fixture(scope="module")
def recip():
    return reciprocating_cam()


@pytest.fixture(scope="module")
def recip_space(recip):
    (cs,) = model_cspaces(recip, accuracy="fast")
    return cs


@pytest.fixture(scope="module")
def optical_spaces():
    return model_cspaces(optical_filter(), accuracy="fast")


def _write(path, doc):
    path.write_text(json.dumps(doc))
    return path


# ------------------------------------------------------------------ resolve_model

@pytest.mark.parametrize("name", sorted(BUILTIN))
def test_builtin_names_resolve_to_their_models(name):
    m = resolve_model(name)
    assert isinstance(m, Model) and m.name == name
    assert m.names == BUILTIN[name]().names


def test_values_pass_through_unchanged(recip):
    pair = recip.build()
    asm = optical_filter().build()
    assert resolve_model(recip) is recip
    assert resolve_model(pair) is pair
    assert resolve_model(asm) is asm


def test_resolve_model_rejects_other_types_and_names(tmp_path):
    with pytest.raises(InputError, match="got float"):
        resolve_model(3.5)
    with pytest.raises(InputError, match="empty string") as e:
        resolve_model("   ")
    assert e.value.name == "model"
    with pytest.raises(InputError, match="unknown model 'no_such_model'") as e:
        resolve_model("no_such_model")
    # the message lists what is allowed
    assert all(n in str(e.value) for n in BUILTIN)
    with pytest.raises(CSpaceError, match="no such file"):
        resolve_model(str(tmp_path / "missing.json"))


@pytest.mark.parametrize("doc, got", [
    ({"format": "cspace_model", "version": 1}, "got format 'cspace_model'"),
    ({"format": "cspace-synthesis-report"}, "got format 'cspace-synthesis-report'"),
    ({"a": 1}, "got no 'format' key"),
    ([1, 2], "got a JSON list"),
])
def test_a_file_of_another_format_is_told_every_format_allowed(tmp_path, doc, got):
    with pytest.raises(FileFormatError, match=got) as e:
        resolve_model(str(_write(tmp_path / "x.json", doc)))
    for fmt in ("'cspace-model'", "'cspace-pair'", "'cspace-assembly'"):
        assert fmt in str(e.value)


def test_pair_file_resolves_to_its_pair_without_the_motion_keys(tmp_path, recip):
    pair = recip.build()
    doc = pair_to_dict(pair)
    doc.update(drive=[0.0, 3.0], q2_start=[0.45], window=[0.0, TWO_PI, -1.0, 1.0],
               deviation=0.02)
    got = resolve_model(str(_write(tmp_path / "p.json", doc)))
    assert isinstance(got, Pair)
    assert got.to_dict() == pair.to_dict()


def test_assembly_and_model_files_resolve(tmp_path, recip):
    from mechanisms.userfile import save_model
    asm = optical_filter().build()
    got = resolve_model(str(_write(tmp_path / "a.json", pair_to_dict(asm))))
    assert isinstance(got, Assembly) and len(got.pairs) == 3
    assert [p.name for p in got.pairs] == [p.name for p in asm.pairs]
    save_model(recip, tmp_path / "m.json")
    m = resolve_model(tmp_path / "m.json")            # a Path works as well as a str
    assert isinstance(m, Model) and m.names == recip.names
    np.testing.assert_array_equal(m.nominal, recip.nominal)


# ------------------------------------------------------------------ pairs and C-spaces

def test_pairs_of_each_kind(recip):
    opt = optical_filter()
    assert len(pairs_of(opt)) == 3
    asm = opt.build()
    assert pairs_of(asm) == asm.pairs
    pair = recip.build()
    assert pairs_of(pair) == (pair,)
    # parameters are applied to a model
    (moved,) = pairs_of(recip, {"cam_x": 0.01})
    assert moved.driver.axis.center == (0.01, 0.0)


def test_model_cspaces_uses_the_model_window_unless_overridden(recip, recip_space):
    assert recip_space.window == tuple(recip.window)
    win = (0.0, TWO_PI, -0.8, 0.9)
    (cs,) = model_cspaces(recip, accuracy="fast", window=win)
    assert cs.window == win
    # the pair of the C-space is the model built at the parameters asked for
    (cs2,) = model_cspaces(recip, {"xr_b": 2.24}, accuracy="fast")
    assert cs2.pair.to_dict() == recip.build({"xr_b": 2.24}).to_dict()
    assert cs2.pair.to_dict() != recip_space.pair.to_dict()


def test_model_cspaces_of_a_fixed_assembly_has_one_space_per_pair():
    asm = optical_filter().build()
    spaces = model_cspaces(asm, accuracy="fast")
    assert [cs.pair.name for cs in spaces] == ["filter1", "filter2", "filter3"]


# ------------------------------------------------------------------ operating point of a file

def test_pair_file_motion_reads_every_key(tmp_path, recip):
    doc = pair_to_dict(recip.build())
    doc.update(drive=[0, 3], q2_start=[0.45], window=[0, 6, -1, 1], deviation=0.05)
    p = _write(tmp_path / "p.json", doc)
    m = pair_file_motion(str(p), 1)
    assert m == {"drive": (0.0, 3.0), "q2_start": (0.45,), "window": (0.0, 6.0, -1.0, 1.0),
                 "deviation": 0.05}
    assert all(isinstance(x, float) for x in m["drive"] + m["window"])
    assert pair_file_start(p, 1) == ((0.0, 3.0), (0.45,))
    assert set(m) == set(MOTION_KEYS)


def test_pair_file_motion_is_empty_where_the_model_states_it(tmp_path, recip):
    from mechanisms.userfile import save_model
    none = dict.fromkeys(MOTION_KEYS)
    plain = _write(tmp_path / "plain.json", pair_to_dict(recip.build()))
    save_model(recip, tmp_path / "m.json")
    assert pair_file_motion(str(plain), 1) == none
    assert pair_file_motion("geneva", 1) == none
    assert pair_file_motion(str(tmp_path / "m.json"), 1) == none
    assert pair_file_motion(str(tmp_path / "absent.json"), 1) == none
    assert pair_file_motion(recip.build(), 1) == none
    assert pair_file_start("geneva", 1) == (None, None)


@pytest.mark.parametrize("key, value, match", [
    ("drive", [1.0, 1.0], "two different ends"),
    ("drive", [0.0], r"\[q1_start, q1_end\]: a JSON list of 2 finite number"),
    ("drive", [True, 1.0], "finite number"),
    ("drive", [0.0, "6"], "finite number"),
    ("q2_start", [0.1, 0.2], r"one follower start per pair \(1\)"),
    ("window", [0.0, 1.0, 2.0, 1.0], "q1_lo < q1_hi and q2_lo < q2_hi"),
    ("window", [1.0, 0.0, -1.0, 1.0], "q1_lo < q1_hi and q2_lo < q2_hi"),
    ("window", [0.0, 1.0, 2.0], r"4 finite number"),
    ("deviation", 0.0, "must be a finite number > 0"),
    ("deviation", -0.1, "must be a finite number > 0"),
    ("deviation", "0.1", "must be a finite number > 0"),
])
def test_pair_file_motion_rejects_bad_values(tmp_path, recip, key, value, match):
    doc = pair_to_dict(recip.build())
    doc[key] = value
    p = _write(tmp_path / "p.json", doc)
    with pytest.raises(InputError, match=match) as e:
        pair_file_motion(str(p), 1)
    assert e.value.name == key
    assert str(p) in str(e.value)                  # the message names the file


def test_default_drive_is_one_turn_of_a_rotating_driver(recip_space):
    assert default_drive(recip_space) == (0.0, TWO_PI)
    shifted = SimpleNamespace(window=(-1.0, 2.0, 0.0, 1.0), periodic=(True, False))
    assert default_drive(shifted) == (-1.0, -1.0 + TWO_PI)
    sliding = SimpleNamespace(window=(-3.0, 7.5, 0.0, 1.0), periodic=(False, True))
    assert default_drive(sliding) == (-3.0, 7.5)


# ------------------------------------------------------------------ simulation

def test_simulate_pairs_defaults(recip_space):
    (sim,) = simulate_pairs([recip_space])
    assert sim.status == SimStatus.OK
    assert sim.q1[0] == 0.0 and sim.q1[-1] == pytest.approx(TWO_PI, abs=1e-12)
    # the default start is the middle of the widest free interval at q1 = 0
    lo, hi, _ = max(recip_space.free_intervals(0.0), key=lambda iv: iv[1] - iv[0])
    assert sim.q2[0] == pytest.approx(0.5 * (lo + hi), abs=1e-12)


def test_simulate_pairs_one_start_for_all_and_count_check(optical_spaces):
    sims = simulate_pairs(optical_spaces, (-math.pi / 2, 0.0), [0.0])
    assert len(sims) == 3
    assert all(s.q2[0] == 0.0 and s.q1[0] == -math.pi / 2 for s in sims)
    assert all(s.q1[-1] == pytest.approx(0.0, abs=1e-12) for s in sims)
    with pytest.raises(InputError, match=r"one follower start per pair \(3\) or one for all, "
                                         r"got 2") as e:
        simulate_pairs(optical_spaces, None, [0.0, 0.0])
    assert e.value.name == "q2_start"


def test_motion_at_uses_the_model_operating_point(recip):
    spaces, sims = motion_at(recip, accuracy="fast")
    (cs,), (sim,) = spaces, sims
    assert cs.window == recip.window
    assert sim.status == SimStatus.OK
    assert sim.q1[0] == recip.drive[0] and sim.q1[-1] == pytest.approx(recip.drive[1])
    assert sim.q2[0] == recip.q2_start[0]


def test_motion_at_reports_a_blocked_start_as_a_result(recip):
    # at q1 = 0 the yoke fits between the fingers for 0.222 < q2 < 0.749 cm only
    blocked = dataclasses.replace(recip, q2_start=(0.9,))
    _, (sim,) = motion_at(blocked, accuracy="fast")
    assert sim.status == SimStatus.START_BLOCKED and not sim.success


# ------------------------------------------------------------------ notes

def test_a_moving_form_closed_follower_needs_no_warning(recip):
    spaces, sims = motion_at(recip, accuracy="fast")
    notes = operating_point_notes(spaces, sims)
    # only where its start in the play is taken up (tests/mechanisms/test_settling_note.py)
    assert [w for w, _ in notes] == [False] and "in the play of its channel" in notes[0][1]


def test_an_ambiguous_default_start_is_a_warning():
    m = geneva()
    spaces, sims = motion_at(m, accuracy="fast")
    ch = spaces[0].start_choice(0.0)
    assert ch.ambiguous                       # four lock positions of the wheel
    notes = operating_point_notes(spaces, sims, [ch])
    warn = [t for w, t in notes if w]
    assert len(warn) == 1 and "state the start" in warn[0] and "'geneva'" in warn[0]
    # one free interval: the note only says which start was taken
    one = StartChoice(0.0, 0.0, ((-0.04, 0.04),), 0, "geneva")
    notes = operating_point_notes(spaces, sims, [one])
    notes = [(w, t) for w, t in notes if "in the play of its channel" not in t]
    assert [w for w, _ in notes] == [False] and "state the start" not in notes[0][1]


def test_a_drive_of_many_turns_is_a_warning(recip):
    """A drive of many whole turns (twelve) runs, and the note says how many;
    a drive written in degrees ([0, 360], 57.3 turns) is refused with what
    radians() gives; the Geneva's four turns are none."""
    spaces, _ = motion_at(recip, accuracy="fast")
    sim = simulate(spaces[0], 0.0, 24 * math.pi, 0.45)
    notes = operating_point_notes(spaces, [sim])
    warn = [t for w, t in notes if w and "turns" in t]
    assert warn == ["the drive runs the driver 12 turns (q1 from 0 to 75.3982 rad); drive "
                    "angles are in rad"]
    with pytest.raises(InputError, match=r"written in degrees\? radians\(0\) and "
                                         r"radians\(360\) are 0 and 6.28319 rad"):
        simulate(spaces[0], 0.0, 360.0, 0.45)
    g_spaces, g_sims = motion_at(geneva(), accuracy="fast")
    assert not any("turns (q1" in t for _, t in operating_point_notes(g_spaces, g_sims))


def test_a_spring_loaded_follower_on_its_stop_never_moves():
    """Held toward increasing q2 the eccentric cam's follower rests on the
    window's top edge: it never moves, and both warnings say so."""
    m = eccentric_cam()
    (cs,) = model_cspaces(m, accuracy="fast")
    sim = simulate(cs, *m.drive, m.q2_start[0], bias=1)
    assert np.ptp(sim.q2) == 0.0
    notes = operating_point_notes([cs], [sim])
    texts = [t for w, t in notes if w]
    assert len(notes) == 2 and len(texts) == 2
    assert "never moves" in texts[0] and "held toward increasing q2" in texts[0]
    assert "q2 stays at 2 cm" in texts[0]
    assert "rests on the window's edge q2 = 2 cm" in texts[1]


def test_typed_warning_and_error():
    assert issubclass(OperatingPointWarning, UserWarning)
    ch = StartChoice(0.0, 0.0, ((-1.0, 0.0), (1.0, 2.0)), 1, "p")
    e = AmbiguousStartError("two starts", [ch])
    assert isinstance(e, InputError) and e.name == "q2_start" and e.choices == (ch,)


def test_follower_unit():
    assert follower_unit(geneva().build()) == "rad"
    assert follower_unit(reciprocating_cam().build()) == "cm"
    assert follower_unit(eccentric_cam().build()) == "cm"


def test_tolerances_beyond_what_the_geometry_takes_are_named(recip):
    from mechanisms.analysis import unbuildable_tolerances
    assert unbuildable_tolerances(recip) == []
    t = recip.tol.copy()
    t[recip.index("tip_r")] = 0.75             # the finger tip radius 0.5 +- 0.75
    found = unbuildable_tolerances(recip.with_tolerances(t))
    # the finger tip cannot have a negative radius (nor, at 1.25, fit its cam)
    assert {n for n, _, _ in found} == {"tip_r"}
    assert found[0][:2] == ("tip_r", pytest.approx(-0.25))
    text = found[0][2]
    assert text.startswith("tip_r = 0.5 - 0.75 = -0.25 (cm) does not build (")
    assert "radius must be > 0" in text and "must cut it or move its nominal" in text
    # a pair has no tolerances
    assert unbuildable_tolerances(recip.build()) == []
