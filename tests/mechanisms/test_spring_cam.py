"""The spring-loaded flat-faced cams: the built-in eccentric cam and the
documented flat-follower cam (``docs/examples/flat_follower_cam.json``).

Closed form of the eccentric cam
--------------------------------
The disc (radius ``disc_r``) is centred ``ecc`` straight below the cam axis
``(cam_x, cam_y)`` at q1 = 0; turned by q1 counter-clockwise its centre lies
at ``(cam_x + ecc sin q1, cam_y - ecc cos q1)``.  A flat face normal to the
slide (y) touches a circle at the circle's top, ``disc_r`` above its centre,
as long as that point lies on the face.  The face lies at ``face + q2``, so a
follower held down on the disc is at

    q2(q1) = cam_y + disc_r - face - ecc cos q1,

whatever ``cam_x`` and the face's width, a lift ``ecc (1 - cos q1)`` above its
lowest point and a stroke of ``2 ecc``.  A variant changes it by ``dc - de cos
q1`` with ``dc = d(cam_y) + d(disc_r) - d(face)``; the deviation the defect
test measures (over the characteristic length L, the cam's reach ``ecc +
disc_r``) is the largest of ``|dc - de cos q1| / L``.

Closed form of the tangent cam
------------------------------
Its top point (farthest along +y) lies on the nose circle while the +y
direction, seen from the cam, lies within the nose arc's normals [t, pi - t],
i.e. for q1 within pi/2 - t of 0 (mod 2 pi), with t = asin((rb - rn) / d);
there the face rests on the nose, ``q2 = d cos q1 + rn - face``, else on the
base circle, ``q2 = rb - face``.
"""

import dataclasses
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from cspace.defects import Reason, is_defective, reference
from cspace.freespace import configuration_space
from cspace.simulate import SimStatus, simulate
from mechanisms.analysis import motion_at, operating_point_notes
from mechanisms.models import BUILTIN, eccentric_cam
from mechanisms.userfile import load_model

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "docs" / "examples" / "flat_follower_cam.json"


def lift(v, q1):
    return v["cam_y"] + v["disc_r"] - v["face"] - v["ecc"] * np.cos(q1)


@pytest.fixture(scope="module")
def cam():
    m = eccentric_cam()
    return m, reference(m, "fast")


def test_the_model_is_built_in_and_spring_loaded(cam):
    m, ref = cam
    assert BUILTIN["eccentric_cam"] is eccentric_cam
    assert m.n == 7 and m.units == "cm"
    np.testing.assert_allclose(m.tol, 0.01)
    assert m.build().bias == -1
    # every other built-in model is form-closed
    for name, factory in BUILTIN.items():
        if name != "eccentric_cam":
            assert all(p.bias == 0 for p in factory().pairs()), name


def test_the_lift_is_the_closed_form_of_an_eccentric_disc(cam):
    """The acceptance test: at the nominal and at seeded variants of the box, the
    simulated follower coordinate is the closed form to 1e-9 of the stroke."""
    m, ref = cam
    sim = ref.sims[0]
    v = m.values()
    assert sim.status == SimStatus.OK and len(sim.q1) > 1000
    stroke = 2 * v["ecc"]
    assert np.max(np.abs(sim.q2 - lift(v, sim.q1))) <= 1e-9 * stroke
    # the nominal is the harmonic lift ecc (1 - cos q1) of stroke 2 ecc
    np.testing.assert_allclose(sim.q2, v["ecc"] * (1 - np.cos(sim.q1)), rtol=0,
                               atol=1e-9 * stroke)
    assert np.ptp(sim.q2) == pytest.approx(stroke, abs=1e-4)
    rng = np.random.default_rng(25)
    for _ in range(8):
        u = m.nominal + m.tol * rng.uniform(-1, 1, m.n)
        (cs,) = [configuration_space(p, "fast", window=m.window) for p in m.pairs(u)]
        r = simulate(cs, *m.drive, m.q2_start[0])
        vu = m.values(u)
        assert r.status == SimStatus.OK
        assert np.max(np.abs(r.q2 - lift(vu, r.q1))) <= 1e-9 * 2 * vu["ecc"]
        assert set(r.contact) == {"cam:disc|follower:face"}


def test_form_closure_stays_the_default_and_leaves_the_follower_behind(cam):
    m, ref = cam
    cs = ref.spaces[0]
    form = configuration_space(dataclasses.replace(m.build(), bias=0), "fast",
                               window=m.window)
    r = simulate(form, *m.drive, m.q2_start[0])
    assert r.status == SimStatus.OK and np.ptp(r.q2) == 0.0
    notes = operating_point_notes([form], [r])
    assert any(w and "never moves" in t for w, t in notes)
    # held down it rides the cam, and the notes say how far
    notes = operating_point_notes(ref.spaces, ref.sims)
    assert not any(w for w, _ in notes)
    assert any("rides the driver, q2 from" in t for _, t in notes)
    assert cs.pair.bias == -1


def test_held_up_it_rests_on_the_window_edge(cam):
    """Held toward increasing q2 nothing bounds the follower: it rests on the
    window's top edge, its travel limit, touching nothing, and is warned of."""
    m, ref = cam
    cs = ref.spaces[0]
    r = simulate(cs, *m.drive, m.q2_start[0], bias=1)
    assert r.status == SimStatus.OK and r.bias == 1
    assert np.all(r.q2 == m.window[3]) and set(r.contact) == {""}
    notes = operating_point_notes([cs], [r])
    assert any(w and "rests on the window's edge q2 = 2 cm" in t for w, t in notes)


def _closed_form_deviation(m, u, x):
    v0, v = m.values(), m.values(u)
    dc = (v["cam_y"] - v0["cam_y"]) + (v["disc_r"] - v0["disc_r"]) - (v["face"] - v0["face"])
    de = v["ecc"] - v0["ecc"]
    # over the nominal's characteristic length (the cam's reach): the metric of
    # the design intent, one length for every variant
    return np.max(np.abs(dc - de * np.cos(x))) / (v0["ecc"] + v0["disc_r"])


def test_the_defect_test_measures_the_closed_form_deviation(cam):
    m, ref = cam
    x = ref.sims[0].q1
    assert not is_defective(m, ref=ref).defective
    names = list(m.names)
    signs = np.zeros(m.n)
    for nm, s in (("cam_y", 1), ("disc_r", 1), ("face", -1), ("ecc", -1)):
        signs[names.index(nm)] = s
    worst = m.nominal + m.tol * signs                 # 0.04 cm of lift at q1 = 0
    r = is_defective(m, worst, ref=ref)
    want = _closed_form_deviation(m, worst, x)
    assert want > ref.d and r.defective and r.reasons == (Reason.DEVIATION,)
    assert r.max_deviation == pytest.approx(want, abs=1e-12)
    # cam_y and face cancel: 0.02 cm at most, healthy
    signs[names.index("face")] = 1
    ok = m.nominal + m.tol * signs
    r = is_defective(m, ok, ref=ref)
    assert not r.defective
    assert r.max_deviation == pytest.approx(_closed_form_deviation(m, ok, x), abs=1e-12)


def test_batched_verdicts_equal_the_full_test_on_the_check_list_and_samples(cam):
    from cspace.batch.margins import defect_margins
    from synthesis.loop import checklist_of, operating_zones
    from synthesis.verify import box_samples
    m, ref = cam
    cl = checklist_of(m, ref, operating_zones(m, ref, "fast"), "fast").array()
    samples = box_samples(m.nominal, m.tol, 300, seed=2025)
    for U in (cl, samples):
        mb = defect_margins(m, U, ref, fallback=False)
        full = np.array([is_defective(m, u, ref=ref).defective for u in U])
        cert = mb.certified
        assert cert.sum() >= 0.8 * len(U)
        np.testing.assert_array_equal(mb.defective[cert], full[cert])
        done = defect_margins(m, U, ref)
        np.testing.assert_array_equal(done.defective, full)
    assert 0 < full.sum() < len(samples)
    # the batch's deviation is the closed form too, at the nominal's samples,
    # over the nominal's characteristic length (the metric of the design intent)
    x = ref.sims[0].q1
    want = np.array([_closed_form_deviation(m, u, x) for u in samples])
    np.testing.assert_allclose(mb.deviation, ref.d - want, rtol=0, atol=1e-12)


def test_synthesis_cuts_the_lift_tolerances_until_the_lift_holds(tmp_path, capsys):
    """``cspace-tol synthesize eccentric_cam --preset fast``: it converges, and in
    the final box the worst lift deviation, in closed form the sum of the four
    tolerances that move the lift, lies within d (over the cam's reach)."""
    from synthesis.cli import main
    out = tmp_path / "s"
    assert main(["synthesize", "eccentric_cam", "--preset", "fast", "--out", str(out)]) == 0
    rep = json.loads((out / "report.json").read_text())
    assert rep["success"] is True
    final = load_model(out / "model.json")
    v, t = final.values(), dict(zip(final.names, final.tol))
    worst = t["cam_y"] + t["disc_r"] + t["face"] + t["ecc"]
    assert worst <= final.deviation * (v["ecc"] + v["disc_r"]) * (1 + 1e-9)
    assert final.build().bias == -1
    # and a seeded Monte Carlo of the final box (half corners), compared with
    # the initial design, finds no defective part
    from synthesis.verify import monte_carlo
    from mechanisms.models import BUILTIN
    mc = monte_carlo(final, 400, seed=3, accuracy="fast", intent=BUILTIN["eccentric_cam"]())
    assert len(mc.defective) == 0, mc


def test_the_documented_flat_follower_cam_rides_its_cam():
    m = load_model(EXAMPLE)
    assert m.build().bias == -1
    (cs,), (sim,) = motion_at(m, accuracy="fast")
    assert sim.status == SimStatus.OK
    v = m.values()
    t = math.asin((v["rb"] - v["rn"]) / v["d"])
    q1 = sim.q1
    on_nose = np.cos(q1) >= math.cos(math.pi / 2 - t)
    want = np.where(on_nose, v["d"] * np.cos(q1) + v["rn"] - v["face"], v["rb"] - v["face"])
    stroke = v["d"] + v["rn"] - v["rb"]
    assert np.max(np.abs(sim.q2 - want)) <= 1e-9 * stroke
    assert sim.q2[0] == pytest.approx(12.0, abs=1e-9)
    assert np.min(sim.q2) == pytest.approx(-1.0, abs=1e-9)


def test_a_pair_file_keeps_its_closure_for_analyze(tmp_path, capsys):
    from cspace.io import save_pair
    from synthesis.cli import main
    m = load_model(EXAMPLE)
    p = save_pair(m.build(), tmp_path / "p.json",
                  {"q2_start": [12.5], "window": [0, 2 * math.pi, -3, 20]})
    assert json.loads(p.read_text())["closure"] == {"bias": -1}
    assert main(["analyze", str(p), "--out", str(tmp_path / "a"), "--no-plots",
                 "--preset", "fast"]) == 0
    err = capsys.readouterr().err
    assert "rides the driver, q2 from -1 to 12 mm" in err and "never moves" not in err


def test_what_the_docs_say_analyze_prints(tmp_path, capsys):
    """The lines docs/model_file.md quotes from ``cspace-tol analyze`` on the
    example are printed as quoted."""
    from synthesis.cli import main
    text = (ROOT / "docs" / "model_file.md").read_text(encoding="utf-8")
    block = re.search(r"`analyze`\nprints, among its progress lines:\n\n```text\n(.*?)```",
                      text, re.S)
    assert block, "the quoted output is missing from docs/model_file.md"
    lines = [ln for ln in block.group(1).splitlines() if ln.strip()]
    assert main(["analyze", str(EXAMPLE), "--out", str(tmp_path / "a"), "--no-plots",
                 "--preset", "fast"]) == 0
    err = capsys.readouterr().err.splitlines()
    for ln in lines:
        assert ln in err, ln
    # and what they say it prints without the closure
    d = json.loads(EXAMPLE.read_text())
    del d["pairs"][0]["closure"]
    (tmp_path / "form.json").write_text(json.dumps(d))
    assert main(["analyze", str(tmp_path / "form.json"), "--out", str(tmp_path / "b"),
                 "--no-plots", "--preset", "fast"]) == 0
    err = capsys.readouterr().err
    assert "output from 12.5 to 12.5" in err
    assert "warning: pair 'cam_follower': the nominal follower never moves" in err
