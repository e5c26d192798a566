"""A converged run whose final box fails its Monte Carlo check goes on with the
defective samples kept as check-list vectors (``SynthesisState.sampled``,
``synthesis.result.with_samples``, ``cspace-tol synthesize --verify-rounds``)."""

import json

import numpy as np
import pytest

from cspace.errors import InputError
from mechanisms.models import reciprocating_cam
from synthesis import synthesize
from synthesis.cli import main
from synthesis.executors import SerialExecutor
from synthesis.result import SynthesisState, SynthesisStatus, with_samples
from synthesis.verify import MonteCarloResult


@pytest.fixture(scope="module")
def converged():
    m = reciprocating_cam()
    states = []
    r = synthesize(m, "fast", executor=SerialExecutor(), on_iteration=states.append)
    assert r.status is SynthesisStatus.CONVERGED
    return m, r, states[-1]


def test_with_samples_keeps_places_in_the_box(converged):
    m, r, st = converged
    c, t = st.nominal, st.tol
    z = np.linspace(-1.0, 1.0, len(c))
    s2 = with_samples(st, [c + z * t])
    assert s2.status is SynthesisStatus.RUNNING
    np.testing.assert_allclose(s2.sampled[0], z, atol=1e-12)
    # the same sample again is kept once; the checkpoint holds them
    assert len(with_samples(s2, [c + z * t]).sampled) == 1
    back = SynthesisState.from_dict(json.loads(json.dumps(s2.to_dict())))
    np.testing.assert_array_equal(back.sampled[0], s2.sampled[0])
    with pytest.raises(InputError, match="samples must lie in the box nominal"):
        with_samples(st, [c + 3 * t])
    with pytest.raises(InputError, match=rf"samples must be \(k, {len(c)}\) finite"):
        with_samples(st, [[1.0, 2.0]])


def test_the_loop_tests_the_kept_samples(converged):
    m, r, st = converged
    z = np.zeros(len(st.nominal))
    z[0] = 0.5
    s2 = with_samples(st, [st.nominal + z * st.tol])
    r2 = synthesize(m, "fast", executor=SerialExecutor(), state=s2)
    assert r2.status is SynthesisStatus.CONVERGED and r2.nit == r.nit + 1
    # one check-list vector more than the converged iteration's
    last, before = r2.history[-1], r.history[-1]
    assert last.counts["checklist"] == before.counts["checklist"] + 1
    assert len(r2.sampled) == 1 and r2.to_dict()["sampled"] == [s2.sampled[0].tolist()]


def test_the_command_line_goes_on_after_a_failed_check(tmp_path, monkeypatch, capsys):
    import importlib
    cli = importlib.import_module("synthesis.cli.main")
    real = cli._verify
    calls = {"n": 0}

    def verify(model, result, args, executor, done=None, stream=None):
        out = real(model, result, args, executor, done=done, stream=stream)
        calls["n"] += 1
        if calls["n"] == 1 or calls["n"] < 0:
            # the first check of the final box finds a "defective" sample
            f = out["final"]
            out["final"] = MonteCarloResult(f.n, f.n_corners, (3,), {"JAM": 1}, f.samples,
                                            f.seed, 0, ("made up",))
        return out

    monkeypatch.setattr(cli, "_verify", verify)
    out = tmp_path / "o"
    code = main(["synthesize", "reciprocating_cam", "--out", str(out), "--preset", "fast",
                 "--executor", "serial", "--no-plots", "--verify", "6"])
    err = capsys.readouterr().err
    assert code == 0, err
    assert "join the check list and the run goes on (2 round(s) of --verify-rounds left)" in err
    assert calls["n"] == 2
    rep = json.loads((out / "report.json").read_text())
    assert len(rep["sampled"]) == 1 and rep["status"] == "CONVERGED"
    assert "The run went on after a failed Monte Carlo check" in (out / "report.md").read_text()
    # --verify-rounds 0: the failed check is only reported
    calls["n"] = 0
    code = main(["synthesize", "reciprocating_cam", "--out", str(tmp_path / "p"), "--preset",
                 "fast", "--executor", "serial", "--no-plots", "--verify", "6",
                 "--verify-rounds", "0"])
    assert code == 1 and calls["n"] == 1
    # rounds that run out: the report says so
    calls["n"] = -10
    code = main(["synthesize", "reciprocating_cam", "--out", str(tmp_path / "r"), "--preset",
                 "fast", "--executor", "serial", "--no-plots", "--verify", "6",
                 "--verify-rounds", "1"])
    assert code == 1
    text = (tmp_path / "r" / "report.md").read_text()
    assert "That check failed too, and no round of `--verify-rounds` was left" in text
    assert main(["synthesize", "reciprocating_cam", "--out", str(tmp_path / "q"),
                 "--verify-rounds", "-1"]) == 2
