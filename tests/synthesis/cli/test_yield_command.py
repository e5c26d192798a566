"""The ``yield`` subcommand (``synthesis.cli.yield_command``), end to end through
``cspace-tol``'s ``main`` on one core (``--executor serial``, ``--preset fast``).

Independent references: the Clopper-Pearson interval from the beta
distribution, and the eccentric cam's closed-form lift ``cam_y + disc_r - face
- ecc cos q1``, which does not depend on ``cam_x``, ``half_w`` or ``thick``."""

import json

import pytest
from scipy.stats import beta

from cspace.io import pair_to_dict
from mechanisms.models import eccentric_cam, reciprocating_cam
from mechanisms.userfile import save_model
from synthesis.cli import build_parser, main
from synthesis.cli.yield_command import cmd_yield
from synthesis.executors import SerialExecutor
from synthesis.statistics import yield_estimate

FAST = ["--preset", "fast", "--executor", "serial"]


def _doc(out):
    return json.loads((out / "yield.json").read_text())


def test_defaults_of_the_subcommand():
    args = build_parser().parse_args(["yield", "geneva", "--out", "d"])
    assert args.func is cmd_yield
    assert (args.model, args.out) == ("geneva", "d")
    assert (args.samples, args.method, args.seed, args.preset) == (2000, "mc", 0, "default")
    assert args.cp is None and args.deviation is None and not args.no_plots
    assert (args.executor, args.workers, args.scheduler) == ("process", None, None)


@pytest.mark.parametrize("argv", [["yield", "geneva"],                        # no --out
                                  ["yield", "geneva", "--out", "d", "--method", "sorm"],
                                  ["yield", "geneva", "--out", "d", "--samples", "many"]])
def test_the_parser_refuses(argv, capsys):
    with pytest.raises(SystemExit) as e:
        build_parser().parse_args(argv)
    assert e.value.code == 2
    assert "usage:" in capsys.readouterr().err


def test_a_run_without_failures_writes_yield_json(tmp_path, capsys):
    out = tmp_path / "new" / "dir"
    code = main(["yield", "reciprocating_cam", "--samples", "20", "--seed", "4", *FAST,
                 "--no-plots", "--out", str(out)])
    assert code == 0
    doc = _doc(out)
    assert doc["model"] == "reciprocating_cam" and doc["units"] == "cm"
    assert doc["preset"] == "fast" and doc["cp"] == 1.0 and doc["method"] == "mc"
    assert doc["samples"] == 20 and doc["seed"] == 4 and doc["files"] == ["yield.json"]
    assert doc["names"] == list(reciprocating_cam().names)
    # the CLI reports what the library computes with the same inputs
    lib = yield_estimate(reciprocating_cam(), 20, seed=4, accuracy="fast",
                         executor=SerialExecutor())
    assert doc["failures"] == lib.failures and doc["probability"] == lib.probability
    assert doc["ci"] == pytest.approx(list(lib.ci), abs=0)
    # no part of 20 fails: the 95 % Clopper-Pearson upper bound is 1 - 0.025^(1/20)
    assert doc["failures"] == 0 and doc["probability"] == 0.0
    assert doc["ci"] == pytest.approx([0.0, 1 - 0.025 ** (1 / 20)], rel=1e-12)
    assert sorted(p.name for p in out.iterdir()) == ["yield.json"]
    err = capsys.readouterr().err
    assert "reciprocating_cam: mc yield, 20 samples, preset fast" in err
    assert "wrote yield.json to" in err


def test_importance_sampling_without_a_failure_region_writes_finite_json(tmp_path, capsys):
    # d = 0.5 cm: no probed corner of the eccentric cam fails, so there is no
    # design point; the run used to stop at a NaN interval end and write nothing
    out = tmp_path / "o"
    assert main(["yield", "eccentric_cam", "--method", "is", "--samples", "100",
                 "--deviation", "0.5", *FAST, "--out", str(out)]) == 0
    text = (out / "yield.json").read_text()
    assert "NaN" not in text and "Infinity" not in text
    doc = json.loads(text)
    assert doc["method"] == "is" and doc["samples"] == 100 and doc["failures"] == 0
    assert doc["ci_method"] == "clopper-pearson" and doc["probability"] == 0.0
    assert doc["ci"] == pytest.approx([0.0, 1 - 0.025 ** (1 / 100)], rel=1e-12)
    assert "no defective start point" in doc["message"]
    assert doc["files"] == ["yield.json"] and doc["design_points"] == []
    assert "wrote yield.json to" in capsys.readouterr().err


@pytest.fixture(scope="module")
def wide_cam(tmp_path_factory):
    """The eccentric cam with +/-0.03 cm: four dimensions add up to 0.12 cm of
    lift against the 0.03 cm the deviation threshold allows, so a good share of
    parts fail."""
    path = tmp_path_factory.mktemp("model") / "cam.json"
    save_model(eccentric_cam(0.03), path)
    return path


def test_failures_give_contributors_and_a_plot(wide_cam, tmp_path):
    out = tmp_path / "o"
    assert main(["yield", str(wide_cam), "--samples", "40", "--seed", "3", *FAST,
                 "--out", str(out)]) == 0
    doc = _doc(out)
    assert doc["files"] == ["yield.json", "contributors.png"]
    assert (out / "contributors.png").stat().st_size > 1000
    n, k = doc["samples"], doc["failures"]
    assert n == 40 and 0 < k < n and doc["probability"] == k / n
    lo, hi = beta.ppf(0.025, k, n - k + 1), beta.ppf(0.975, k + 1, n - k)
    assert doc["ci"] == pytest.approx([lo, hi], rel=1e-9)
    assert doc["ci_method"] == "clopper-pearson"
    assert set(doc["by_reason"]) == {"DEVIATION"}
    assert doc["design_points"] and doc["tests"] > doc["samples"]
    # the lift does not depend on these three: they contribute nothing
    c = doc["contributors"]
    assert set(c) == set(eccentric_cam().names)
    assert c["cam_x"] == c["half_w"] == c["thick"] == 0.0
    assert min(c["cam_y"], c["disc_r"], c["face"], c["ecc"]) > 0.1
    assert sum(c.values()) == pytest.approx(1.0, abs=1e-9)


def test_no_plots_and_cp_are_passed_on(wide_cam, tmp_path):
    out = tmp_path / "o"
    assert main(["yield", str(wide_cam), "--samples", "30", "--seed", "3", "--cp", "2.0",
                 "--deviation", "0.05", *FAST, "--no-plots", "--out", str(out)]) == 0
    doc = _doc(out)
    assert doc["cp"] == 2.0 and doc["files"] == ["yield.json"]
    assert not (out / "contributors.png").exists()
    lib = yield_estimate(eccentric_cam(0.03), 30, seed=3, accuracy="fast", d=0.05, cp=2.0,
                         executor=SerialExecutor())
    assert doc["failures"] == lib.failures and doc["probability"] == lib.probability


def test_a_fixed_pair_is_refused_before_any_output(tmp_path, capsys):
    pair = tmp_path / "pair.json"
    pair.write_text(json.dumps(pair_to_dict(reciprocating_cam().build())))
    out = tmp_path / "o"
    assert main(["yield", str(pair), "--samples", "5", *FAST, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: yield needs a parametric model")
    assert "a fixed Pair" in err
    assert not out.exists()


@pytest.mark.parametrize("bad", ["no_such_model", ""])
def test_unknown_models_are_refused(tmp_path, capsys, bad):
    assert main(["yield", bad, "--samples", "5", *FAST, "--out", str(tmp_path / "o")]) == 2
    assert capsys.readouterr().err.startswith("error: ")
    assert not (tmp_path / "o").exists()


def test_out_must_be_a_folder(tmp_path, capsys):
    f = tmp_path / "file.txt"
    f.write_text("x")
    assert main(["yield", "reciprocating_cam", "--samples", "5", *FAST, "--out", str(f)]) == 2
    assert "--out must name a folder" in capsys.readouterr().err
    assert f.read_text() == "x"


def test_bad_sample_counts_are_typed_errors(tmp_path, capsys):
    assert main(["yield", "reciprocating_cam", "--samples", "0", *FAST,
                 "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[-1] == "error: the number of samples must be an int in [1, 1000000], got 0"
    # refused before anything is written: no folder, no progress line
    assert not (tmp_path / "o").exists()
    assert len(err) == 1


@pytest.mark.parametrize("opt, msg", [
    (["--cp", "0"], "error: cp must be a finite number > 0 (a process capability, e.g. 1.33), "
                    "got 0.0"),
    (["--workers", "0"], "error: workers must be an int >= 1, got 0"),
    # a command line cannot pass a Generator, which the API's message offers
    (["--seed", "-3"], "error: --seed must be an int >= 0, got -3"),
    # the folder was made before this was refused
    (["--executor", "dask"], "error: --executor dask needs --scheduler ADDR (e.g. "
                             "tcp://host:8786)"),
    (["--scheduler", "tcp://h:1"], "error: --scheduler is for --executor dask, got --executor "
                                   "serial"),
])
def test_bad_options_are_refused_before_the_output_folder_is_made(tmp_path, capsys, opt, msg):
    out = tmp_path / "o"
    assert main(["yield", "reciprocating_cam", "--samples", "10", *FAST, "--out", str(out),
                 *opt]) == 2
    assert capsys.readouterr().err.strip().splitlines()[-1] == msg
    assert not out.exists()


def _stopping_after(monkeypatch, calls: int):
    """Make the ``calls + 1``-th batch of defect tests raise KeyboardInterrupt
    (Ctrl-C in the middle of an estimate)."""
    import synthesis.executors as ex
    real = ex.batch_task
    seen = {"n": 0}

    def task(*a):
        seen["n"] += 1
        if seen["n"] > calls:
            raise KeyboardInterrupt
        return real(*a)

    monkeypatch.setattr(ex, "batch_task", task)
    return seen


@pytest.mark.parametrize("method", ["mc", "is"])
def test_a_stopped_estimate_resumes_to_the_uninterrupted_result(wide_cam, tmp_path, capsys,
                                                                  monkeypatch, method):
    args = ["yield", str(wide_cam), "--samples", "40", "--seed", "5", "--method", method,
            *FAST, "--no-plots"]
    whole = tmp_path / "whole"
    assert main([*args, "--out", str(whole)]) == 0
    out = tmp_path / "o"
    with monkeypatch.context() as mp:
        _stopping_after(mp, 3)
        assert main([*args, "--out", str(out)]) == 130
    err = capsys.readouterr().err
    ckpt = out / "yield_checkpoint.json"
    assert "interrupted: the estimate was stopped; its" in err and "--resume" in err
    assert ckpt.is_file() and not (out / "yield.json").exists()
    kept = len(json.loads(ckpt.read_text())["partial"]["tests"])
    assert kept > 0
    # a new run into the folder is refused: the stopped one would be lost
    assert main([*args, "--out", str(out)]) == 2
    assert "holds a stopped estimate" in capsys.readouterr().err
    assert ckpt.is_file()
    # --resume: only what had not finished is tested; the result is the whole run's
    seen = _stopping_after(monkeypatch, 10 ** 6)
    assert main([*args, "--out", str(out), "--resume"]) == 0
    err = capsys.readouterr().err
    assert f"resumed with {kept} finished defect tests" in err
    # the resumed run asks for every kept test again (each counted once)
    import re
    reused, done = map(int, re.search(r"(\d+) of the checkpoint's (\d+) finished tests reused",
                                      err).groups())
    assert reused == done == kept
    assert seen["n"] >= 1
    assert _doc(out) == _doc(whole)
    assert not ckpt.exists()


def test_resume_needs_the_same_settings_and_a_checkpoint(wide_cam, tmp_path, capsys,
                                                         monkeypatch):
    args = ["yield", str(wide_cam), "--samples", "30", "--seed", "2", *FAST, "--no-plots"]
    out = tmp_path / "o"
    assert main([*args, "--out", str(out), "--resume"]) == 2
    assert "there is no stopped estimate to continue" in capsys.readouterr().err
    with monkeypatch.context() as mp:
        _stopping_after(mp, 1)
        assert main([*args, "--out", str(out)]) == 130
    capsys.readouterr()
    before = (out / "yield_checkpoint.json").read_text()
    assert main([*args[:-1], "--seed", "3", "--no-plots", "--out", str(out), "--resume"]) == 2
    err = capsys.readouterr().err
    assert "was started with other settings (seed: checkpoint 2, given 3)" in err
    assert (out / "yield_checkpoint.json").read_text() == before
    assert main([*args, "--out", str(out), "--resume", "--fresh"]) == 2
    assert "--resume and --fresh exclude each other" in capsys.readouterr().err
    (out / "yield_checkpoint.json").write_text("{not json")
    assert main([*args, "--out", str(out), "--resume"]) == 2
    assert "is not a readable yield checkpoint" in capsys.readouterr().err
    # --fresh starts over
    assert main([*args, "--out", str(out), "--fresh"]) == 0
    assert not (out / "yield_checkpoint.json").exists() and _doc(out)["samples"] == 30


def test_the_library_takes_a_memo():
    from synthesis.memo import TestMemo
    m = eccentric_cam(0.03)
    whole = yield_estimate(m, 20, seed=1, accuracy="fast", executor=SerialExecutor(),
                           search=False)
    memo = TestMemo(1, m.nominal, m.tol)
    first = yield_estimate(m, 20, seed=1, accuracy="fast", executor=SerialExecutor(),
                           search=False, memo=memo)
    assert len(memo) == first.tests and memo.hits == 0
    again = yield_estimate(m, 20, seed=1, accuracy="fast", executor=SerialExecutor(),
                           search=False, memo=memo)
    assert memo.hits == again.tests
    assert whole.to_dict() == first.to_dict() == again.to_dict()
    from cspace.errors import InputError
    with pytest.raises(InputError, match="memo must be a synthesis.memo.TestMemo or None, got "
                                         "dict"):
        yield_estimate(m, 5, memo={}, executor=SerialExecutor())


def test_no_search_runs_the_samples_alone(wide_cam, tmp_path, capsys):
    """``--no-search``: the same samples and failures as with the search, no
    tests beyond the samples, no design points; refused with ``--method is``."""
    out = tmp_path / "o"
    assert main(["yield", str(wide_cam), "--samples", "40", "--seed", "3", *FAST,
                 "--no-search", "--no-plots", "--out", str(out)]) == 0
    doc = _doc(out)
    lib = yield_estimate(eccentric_cam(0.03), 40, seed=3, accuracy="fast",
                         executor=SerialExecutor())
    assert doc["failures"] == lib.failures > 0 and doc["tests"] == 40
    assert not doc["design_points"] and lib.design_points
    capsys.readouterr()
    assert main(["yield", str(wide_cam), "--method", "is", "--no-search", *FAST,
                 "--out", str(tmp_path / "x")]) == 2
    assert "--no-search applies to --method mc only" in capsys.readouterr().err
