"""Bad input at the command line and its API entry points: one clear line and
exit code 2, nothing written outside --out, and an earlier run's files kept."""

import copy
import json
from pathlib import Path

import numpy as np
import pytest

from cspace.errors import FileFormatError, InputError, ParameterError
from synthesis.cli import main

EXAMPLE = Path(__file__).resolve().parents[3] / "docs" / "examples" / "flat_follower_cam.json"


def _model(tmp_path, edit, name="m.json"):
    d = json.loads(EXAMPLE.read_text())
    edit(d)
    p = tmp_path / name
    p.write_text(json.dumps(d))
    return p


def _err(capsys):
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return err


def test_out_that_is_a_file_is_refused(tmp_path, capsys):
    f = tmp_path / "afile"
    f.write_text("keep")
    for cmd in (["analyze", "reciprocating_cam", "--no-plots"],
                ["synthesize", "reciprocating_cam", "--executor", "serial"]):
        assert main([*cmd, "--out", str(f)]) == 2
        assert "is a file" in _err(capsys)
    assert main(["analyze", "reciprocating_cam", "--no-plots", "--out", str(f / "x")]) == 2
    assert "--out must name a folder that can be created and written" in _err(capsys)
    assert f.read_text() == "keep"


def test_failed_analysis_keeps_the_earlier_files(tmp_path, capsys):
    out = tmp_path / "keep"
    assert main(["analyze", "reciprocating_cam", "--no-plots", "--out", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    bad = _model(tmp_path, lambda d: d.update(q2_start=[-2.0]))   # a blocked start
    assert main(["analyze", str(bad), "--no-plots", "--out", str(out)]) == 2
    _err(capsys)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_pair_names_never_leave_the_output_folder(tmp_path, capsys):
    def two_pairs(d):
        p2 = copy.deepcopy(d["pairs"][0])
        p2["name"] = "../../ESCAPED $x$"
        d["pairs"].append(p2)
        d["q2_start"] = d["q2_start"] * 2

    m = _model(tmp_path, two_pairs)
    out = tmp_path / "deep" / "out"
    assert main(["analyze", str(m), "--preset", "fast", "--out", str(out)]) == 0
    _err(capsys)
    assert all(out in p.parents for p in tmp_path.rglob("*ESCAPED*"))
    names = {p.name for p in out.iterdir()}
    assert {"cspace_cam_follower.json", "cspace_ESCAPED_x.json", "zones_ESCAPED_x.png"} <= names


def test_same_pair_names_get_distinct_files():
    from synthesis.cli.report import file_suffixes
    assert file_suffixes(["a", "a", "b/c", "..", ""]) == ["_a_0", "_a_1", "_b_c", "_pair_3",
                                                          "_pair_4"]


def test_dollar_in_names_plots(tmp_path, capsys):
    m = _model(tmp_path, lambda d: d["pairs"][0]["parts"][0].update(name="$^$"))
    assert main(["analyze", str(m), "--preset", "fast", "--out", str(tmp_path / "o")]) == 0
    _err(capsys)
    assert (tmp_path / "o" / "parts.png").stat().st_size > 0


def test_zero_tolerances_analyse(tmp_path, capsys):
    m = _model(tmp_path, lambda d: [p.update(tol=0) for p in d["parameters"]])
    assert main(["analyze", str(m), "--preset", "fast", "--no-plots",
                 "--out", str(tmp_path / "o")]) == 0
    z = json.loads((tmp_path / "o" / "zones.json").read_text())
    assert z["bands"]


@pytest.mark.parametrize("opts, says", [
    (["--deviation", "inf"], "--deviation must be a finite number"),
    (["--seed", "-5", "--verify", "4"], "seed must be an int >= 0"),
    (["--verify", "100000000000000000000"], "number of samples must be an int"),
    (["--resume", "--fresh"], "exclude each other"),
    (["--scheduler", "tcp://h:1"], "--scheduler is for --executor dask"),
    (["--executor", "process", "--workers", "100000"], "workers must be at most"),
])
def test_synthesize_options_are_checked_before_any_work(tmp_path, capsys, opts, says):
    out = tmp_path / "o"
    ex = [] if "--executor" in opts else ["--executor", "serial"]
    assert main(["synthesize", "reciprocating_cam", "--preset", "fast", "--no-plots",
                 "--out", str(out), *ex, *opts]) == 2
    assert says in _err(capsys)
    assert not out.exists() or not any(out.iterdir())


def test_bad_dask_scheduler_is_a_clear_error(tmp_path, capsys):
    pytest.importorskip("distributed")
    assert main(["synthesize", "reciprocating_cam", "--executor", "dask", "--scheduler",
                 "garbage", "--out", str(tmp_path / "o")]) == 2
    assert "cannot connect to the dask scheduler" in _err(capsys)


@pytest.mark.parametrize("edit, says", [
    (lambda c: c.update(tol=c["tol"][:1]), "tol must hold 11 values"),
    (lambda c: c.update(d=-1), "d must be a positive finite number"),
    (lambda c: c.update(d=10 ** 400), "OverflowError"),
    (lambda c: c.update(removed=[[1.0], [1.0, 2.0, 3.0]]), "removed"),
    (lambda c: c.update(tol=[-0.1] * len(c["tol"])), "tol must be >= 0"),
])
def test_damaged_checkpoint_is_refused_before_the_run(tmp_path, capsys, edit, says):
    out = tmp_path / "o"
    args = ["synthesize", "reciprocating_cam", "--preset", "fast", "--executor", "serial",
            "--no-plots", "--out", str(out)]
    assert main([*args, "--max-iter", "1"]) == 1
    _err(capsys)
    ck = out / "checkpoint.json"
    c = json.loads(ck.read_text())
    edit(c)
    ck.write_text(json.dumps(c))
    assert main([*args, "--resume", "--max-iter", "2"]) == 2
    err = _err(capsys)
    assert says in err and err.count("damaged checkpoint") == 1


def test_huge_json_numbers_are_file_errors(tmp_path):
    from mechanisms.userfile import load_model
    m = _model(tmp_path, lambda d: d["parameters"][0].update(nominal=10 ** 400))
    with pytest.raises(FileFormatError, match="finite number"):
        load_model(m)


def test_long_let_chain_in_reverse_order(tmp_path):
    from mechanisms.userfile import load_model

    def chain(d):
        n = 3000
        d["let"] = d["let"] + [{"name": f"z{i}", "value": f"z{i + 1} + 0"} for i in range(n)] \
            + [{"name": f"z{n}", "value": "1.0"}]

    assert load_model(_model(tmp_path, chain)).n > 0


def test_model_values_must_be_numbers(models):
    m = models["geneva"]
    for bad in (True, "3.2", 10 ** 400):
        with pytest.raises(ParameterError):
            m.vector({"lock_r": bad})
    with pytest.raises(ParameterError, match="tolerances must be"):
        m.with_tolerances("x")
    assert m.with_tolerances({"lock_r": 0.01}).tol[m.index("lock_r")] == 0.01


def test_monte_carlo_inputs_are_checked(models):
    from synthesis.verify import box_samples, monte_carlo
    m = models["reciprocating_cam"]
    with pytest.raises(InputError, match="seed"):
        box_samples(m.nominal, m.tol, 4, seed=-1)
    with pytest.raises(InputError, match="one length"):
        box_samples([1.0, 2.0], [1.0], 4)
    with pytest.raises(InputError, match=">= 0"):
        box_samples([1.0], [-1.0], 4)
    with pytest.raises(InputError, match="executor"):
        monte_carlo(m, 4, executor="serial")
    with pytest.raises(InputError, match="parametric model"):
        monte_carlo(m.build(), 4)


def test_params_file_errors(tmp_path, capsys):
    out = tmp_path / "x.dxf"
    pytest.importorskip("ezdxf")
    assert main(["export-dxf", "reciprocating_cam", "--out", str(out), "--params",
                 str(tmp_path / "missing.json")]) == 2
    assert "no such file" in _err(capsys)
    assert main(["export-dxf", "reciprocating_cam", "--out", str(out), "--params",
                 '{"f0": 1, "f0": 2}']) == 2
    assert "more than once" in _err(capsys)
    assert main(["export-dxf", "reciprocating_cam", "--out", str(out), "--params",
                 '{"f0": true}']) == 2
    assert "must be a number" in _err(capsys)
    assert not out.exists()


def test_dxf_layer_zero_and_damaged_files(tmp_path, capsys):
    ezdxf = pytest.importorskip("ezdxf")
    from mechanisms.dxf import export_dxf, import_dxf
    from mechanisms.models import reciprocating_cam
    from cspace.geometry import Pair, Part
    p = reciprocating_cam().build()
    renamed = Pair(Part("0", p.driver.loops, p.driver.axis),
                   Part("Defpoints", p.follower.loops, p.follower.axis), p.units, p.name)
    f = tmp_path / "p.dxf"
    export_dxf(renamed, f)
    doc = ezdxf.readfile(str(f))
    assert {e.dxf.layer for e in doc.modelspace()} == {"0", "Defpoints"}
    cut = tmp_path / "cut.dxf"
    cut.write_bytes(f.read_bytes()[:2000])
    parts = [{"layer": "0", "name": "cam", "axis": {"type": "rotation", "center": [0, 0]}},
             {"layer": "Defpoints", "name": "yoke",
              "axis": {"type": "translation", "direction": [1, 0]}}]
    with pytest.raises(FileFormatError, match="not a valid DXF"):
        import_dxf(cut, parts=parts)
    with pytest.raises(FileFormatError, match="is a folder"):
        import_dxf(tmp_path, parts=parts)
    with pytest.raises(InputError, match="cannot convert"):
        import_dxf(f, parts=parts, units="furlong")
    doc.header["$INSUNITS"] = 9   # mils
    mil = tmp_path / "mil.dxf"
    doc.saveas(str(mil))
    a = import_dxf(f, parts=parts)
    b = import_dxf(mil, parts=parts, units="in")
    assert np.isclose(b.size, a.size / 1000.0)


def test_analyze_window_applies_to_zones_and_motion(tmp_path, capsys):
    # a window that does not hold the drive is refused, not silently used for
    # the C-space alone
    assert main(["analyze", "reciprocating_cam", "--window", "0", "1", "0", "1", "--no-plots",
                 "--out", str(tmp_path / "o")]) == 2
    assert "outside the C-space window" in _err(capsys)
    assert main(["analyze", "", "--out", str(tmp_path / "o")]) == 2
    assert "empty string" in _err(capsys)


def test_max_iter_zero_says_nothing_was_tested(models):
    from synthesis.executors import SerialExecutor
    from synthesis.loop import synthesize
    r = synthesize(models["reciprocating_cam"], "fast", max_iter=0, executor=SerialExecutor())
    assert r.status.name == "MAX_ITER" and "no variant was tested" in r.message


def test_deviation_threshold_is_checked_everywhere(models):
    from cspace.defects import is_defective, reference
    from synthesis.verify import monte_carlo
    m = models["reciprocating_cam"]
    for bad in (-1, 0.0, float("inf"), "x"):
        with pytest.raises(InputError, match="d must be a finite number > 0"):
            monte_carlo(m, 4, d=bad)
        with pytest.raises(InputError, match="d must be a finite number > 0"):
            reference(m, "fast", d=bad)
    with pytest.raises(InputError, match="d must be a finite number > 0"):
        is_defective(m, m.nominal, d=-1.0, ref=reference(m, "fast"))


def test_pair_files_are_checked_as_strictly_as_model_files(models, tmp_path):
    from cspace.io import pair_from_dict, pair_to_dict
    good = pair_to_dict(models["reciprocating_cam"].build())
    pair_from_dict(good)

    def bad(edit, says):
        d = json.loads(json.dumps(good))
        edit(d)
        with pytest.raises(FileFormatError, match=says):
            pair_from_dict(d)

    bad(lambda d: d.update(nmae="x"), "unknown keys \\['nmae'\\] in a pair")
    bad(lambda d: d["parts"][0].update(colour="red"), "unknown keys \\['colour'\\] in a part")
    bad(lambda d: d["parts"][0]["axis"].update(orgin=[0, 0]), "in a rotation axis")
    bad(lambda d: d.update(name=5), "'name' must be a non-empty string")
    bad(lambda d: d["parts"][1].update(name=d["parts"][0]["name"]), "different names")
    asm = pair_to_dict(models["optical_filter"].build())
    asm["pairs"][1]["units"] = "in"
    with pytest.raises(FileFormatError, match="one length unit"):
        pair_from_dict(asm)
    asm["pairs"][1]["units"] = asm["pairs"][0]["units"]
    asm["pairs"][1]["name"] = asm["pairs"][0]["name"]
    with pytest.raises(FileFormatError, match="must differ"):
        pair_from_dict(asm)


def test_doubtful_model_values_are_refused(tmp_path):
    from cspace.errors import CSpaceError, ExpressionError, InvalidModelError
    from mechanisms.userfile import load_model
    with pytest.raises(ExpressionError, match="too large for a float"):
        load_model(_model(tmp_path, lambda d: d["let"].append({"name": "big",
                                                                "value": "1e999 * rb"})))
    with pytest.raises(InvalidModelError, match="drive must be two different"):
        load_model(_model(tmp_path, lambda d: d.update(drive=[1, 1])))
    m = load_model(_model(tmp_path, lambda d: d.update(q2_start=[1e6])))
    from cspace.defects import reference
    with pytest.raises(CSpaceError, match="outside the follower window"):
        reference(m, "fast")


def test_bad_cost_is_refused_before_the_signal_handlers_change(tmp_path, capsys):
    """A bad --shift-cost exits 2 and leaves the caller's SIGINT/SIGTERM handlers."""
    import signal
    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    assert main(["synthesize", "reciprocating_cam", "--executor", "serial",
                 "--shift-cost", "r_base=-1", "--out", str(tmp_path / "o")]) == 2
    assert "--shift-cost must be NAME=W" in _err(capsys)
    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before


def test_a_run_leaves_the_callers_warning_filters(tmp_path, capsys):
    """The run hides the operating-point warnings it logs itself, and restores
    the caller's warning filters afterwards."""
    import warnings

    from mechanisms.analysis import OperatingPointWarning
    code = main(["synthesize", "reciprocating_cam", "--executor", "serial", "--preset", "fast",
                 "--max-iter", "1", "--no-plots", "--out", str(tmp_path / "o")])
    assert code in (0, 1)
    # (imports during the run, such as scipy's, may add filters of their own)
    assert not any(f[2] is OperatingPointWarning for f in warnings.filters)
    _err(capsys)
