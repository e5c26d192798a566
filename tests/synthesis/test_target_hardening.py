"""The target-yield stopping rule and the ``yield`` command line, hardened:
a confirmed ``is`` target, a complete reproduce command, an unconfirmable
target refused up front, options checked before DIR, a self-describing
``yield.json`` and SIGTERM."""

import json
import shlex
from types import SimpleNamespace

import pytest

import synthesis.statistics as statistics
from cspace.errors import InputError
from synthesis.cli import main
from synthesis.target import YieldTarget, estimate_design, mc_floor, samples_needed


def _fake_estimates(monkeypatch, cis, plain=False):
    """yield_estimate replaced: seed s gives the interval cis[s] (ppm); with
    ``plain``, importance sampling found no design point (plain samples)."""
    def fake(design, n, *, seed, **kw):
        lo, hi = (1e-6 * c for c in cis[seed])
        return SimpleNamespace(method="is", probability=(lo + hi) / 2, ppm=5e5 * (lo + hi),
                               ci=(lo, hi), failures=100, samples=n, tests=n + 9,
                               ci_method="clopper-pearson" if plain else "weighted-normal",
                               design_points=() if plain else ("p",),
                               message="plain Monte Carlo" if plain else "importance sampling")
    monkeypatch.setattr(statistics, "yield_estimate", fake)


def test_an_is_estimate_that_drew_plain_samples_says_so(monkeypatch):
    """Importance sampling without a failure region to sample around draws
    plain samples: the estimate says so (``plain``, its ``ci_method``), and
    the run's advice is more samples, not the method it already uses."""
    _fake_estimates(monkeypatch, {0: (242.0, 7206.0)}, plain=True)
    ye = estimate_design(None, None, YieldTarget.parse("99.9%", method="is", samples=1000),
                         "fast", None, None)
    assert not ye["met"] and ye["plain"] and ye["ci_method"] == "clopper-pearson"
    import sys
    cli = sys.modules["synthesis.cli.main"]       # the module, not the function
    t = YieldTarget.parse("99.9%", method="is", samples=1000)
    res = SimpleNamespace(target=t.to_dict(), yield_estimate=ye)
    logged = []
    monkeypatch.setattr(cli, "_log", logged.append)
    assert cli._target_met(res) is False
    assert "(more --yield-samples; importance sampling found no failure region" in logged[0]
    assert "--yield-method is" not in logged[0]


def test_an_is_target_met_by_one_seed_only_is_unconfirmed(monkeypatch):
    _fake_estimates(monkeypatch, {0: (1.33, 2.52), 1: (2.9, 4.1)})
    ye = estimate_design(None, None, YieldTarget.parse("3ppm", method="is", samples=400),
                         "fast", None, None)
    assert not ye["met"] and not ye["confirmed"] and "seed 1" in ye["unconfirmed"]
    assert ye["check"]["seed"] == 1 and ye["tests"] == 2 * 409


def test_an_is_target_two_seeds_agree_on_is_met(monkeypatch):
    _fake_estimates(monkeypatch, {0: (1.33, 2.52), 1: (1.2, 2.4)})
    ye = estimate_design(None, None, YieldTarget.parse("3ppm", method="is", samples=400),
                         "fast", None, None)
    assert ye["met"] and ye["confirmed"] and "unconfirmed" not in ye


def test_disjoint_is_intervals_are_unconfirmed(monkeypatch):
    _fake_estimates(monkeypatch, {0: (1.33, 2.52), 1: (0.1, 0.5)})
    ye = estimate_design(None, None, YieldTarget.parse("3ppm", method="is", samples=400),
                         "fast", None, None)
    assert not ye["met"] and "overlap" in ye["unconfirmed"]


def _target_result(search="margin", status="TARGET_YIELD"):
    t = YieldTarget(0.999997, samples=400, method="is", cp=1.33, seed=5)
    return SimpleNamespace(accuracy={"name": "fast"}, patience=4, two_sided=True, d=0.04,
                           removal="lp", status=SimpleNamespace(name=status), nit=1,
                           search=search, target=t.to_dict()), t


def test_the_reproduce_command_repeats_the_target():
    from synthesis.cli.main import _target, build_parser
    from synthesis.cli.report import reproduce_command
    r, t = _target_result()
    cmd = reproduce_command(r)
    args = build_parser().parse_args(shlex.split(cmd)[1:])
    assert _target(args) == t


def test_the_reproduce_python_repeats_the_target(monkeypatch):
    import synthesis
    from synthesis.cli.report import reproduce_python
    r, t = _target_result()
    seen = {}
    monkeypatch.setattr(synthesis, "synthesize", lambda *a, **kw: seen.update(kw))
    exec(reproduce_python(r), {"model": "m"})
    assert YieldTarget.from_dict(t.to_dict()) == seen["target_yield"]


def test_an_mc_target_its_samples_can_never_confirm_is_refused_before_dir(tmp_path, capsys):
    assert samples_needed(1e-3) > 3000 and mc_floor(400) > 1e-3 >= mc_floor(samples_needed(1e-3))
    out = tmp_path / "o"
    code = main(["synthesize", "eccentric_cam", "--out", str(out), "--preset", "fast",
                 "--target-yield", "1000ppm", "--yield-samples", "400"])
    err = capsys.readouterr().err
    assert code == 2 and not out.exists()
    assert f"--yield-samples {samples_needed(1e-3)} or more" in err and "is" in err


def test_a_clean_worst_case_without_a_confirmed_target_exits_1(capsys):
    from synthesis.cli.main import _target_met
    r = SimpleNamespace(target={"target": 0.9999}, yield_estimate={"met": False})
    assert not _target_met(r) and "target not met" in capsys.readouterr().err
    assert _target_met(SimpleNamespace(target=None, yield_estimate=None))


def test_an_unconfirmed_is_target_says_what_plain_monte_carlo_would_need(capsys):
    """With --yield-method is at a design whose worst case is clean, importance
    sampling has no failure region and estimates by plain Monte Carlo, which
    100 samples cannot confirm 100 ppm with: the message says how many could."""
    from synthesis.cli.main import _target_met
    r = SimpleNamespace(target={"target": 0.9999, "ppm": 100.0, "method": "is"},
                        yield_estimate={"met": False, "plain": True})
    assert not _target_met(r)
    err = capsys.readouterr().err
    assert (f"plain Monte Carlo confirms 100 ppm from {samples_needed(1e-4):,} samples "
            f"without a failure") in err and "--verify N" in err


def test_a_target_of_1_says_what_is_allowed():
    with pytest.raises(InputError, match=r"0 < Y < 1.*ppm"):
        YieldTarget.parse("1")


def test_yield_refuses_a_bad_deviation_before_dir(tmp_path):
    out = tmp_path / "o"
    assert main(["yield", "eccentric_cam", "--out", str(out), "--deviation", "-1"]) == 2
    assert not out.exists()


def test_yield_json_says_d_cp_units_and_distributions(tmp_path):
    from cspace.defects import reference
    from mechanisms.analysis import resolve_model
    out = tmp_path / "o"
    assert main(["yield", "reciprocating_cam", "--out", str(out), "--preset", "fast",
                 "--samples", "100", "--executor", "serial", "--no-plots"]) == 0
    doc = json.loads((out / "yield.json").read_text())
    assert doc["cp"] == 1.0
    assert doc["d"] == pytest.approx(reference(resolve_model("reciprocating_cam"), "fast").d)
    p = doc["parameters"][0]
    assert p["unit"] and p["distribution"]["kind"] == "truncated_normal"
    assert "vector_units" in doc


def test_yield_stopped_by_sigterm_exits_143_and_writes_nothing(tmp_path, monkeypatch, capsys):
    from synthesis.cli.main import _Terminated

    def stopped(*a, **kw):
        raise _Terminated()
    monkeypatch.setattr(statistics, "yield_estimate", stopped)
    out = tmp_path / "o"
    assert main(["yield", "reciprocating_cam", "--out", str(out), "--preset", "fast",
                 "--samples", "100", "--executor", "serial"]) == 143
    assert not (out / "yield.json").exists() and "terminated" in capsys.readouterr().err
