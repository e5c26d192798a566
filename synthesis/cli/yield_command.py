"""The ``yield`` subcommand of the command line: statistical yield of a model.

yield MODEL --out DIR [--samples N] [--method mc|is] [--cp CP] [--seed S]
      [--preset P] [--deviation D] [--executor process|serial|dask] [--workers N]
      [--scheduler ADDR] [--no-plots] [--resume | --fresh]
    Estimates the probability that a part made with the model's distributions
    (each parameter's ``distribution``, default a normal of Cp 1 truncated at
    its tolerance) is defective (:func:`synthesis.statistics.yield_estimate`),
    and writes ``yield.json`` and, when it found a design point, ``contributors.png``
    (``yield.json``'s ``files`` lists them).  ``yield.json`` also
    holds what reads or reruns it: the threshold ``d`` used, the Cp used,
    each parameter's unit and distribution (every vector, design points'
    ``x`` included, is in these units: rad for an angle).  Every option is
    checked before DIR is made.  Exit status 0, 2 bad input, 130 stopped by
    SIGINT (Ctrl-C), 143 stopped by SIGTERM.

    The finished defect tests are kept in ``DIR/yield_checkpoint.json``
    (written atomically every 30 s while tests finish, and when the run is
    stopped): the same command with ``--resume`` continues a stopped
    estimate, testing only what was not finished, and gives the result of an
    uninterrupted run (the samples and the design-point search follow from
    the seed and the tests' results).  The checkpoint records the model's
    fingerprint and every option that changes the result; ``--resume`` with
    other ones is refused, and so is a new run into a DIR holding a stopped
    one, unless ``--fresh`` (which discards it).  It is removed once
    ``yield.json`` is written.  One run at a time writes into DIR (a lock,
    :mod:`synthesis.cli.outlock`).
"""

from __future__ import annotations

import sys
import time

__all__ = ["register", "cmd_yield", "CHECKPOINT"]

#: The stopped estimate's finished tests, in the output folder.
CHECKPOINT = "yield_checkpoint.json"

#: The ``format`` of :data:`CHECKPOINT`.
FORMAT = "cspace-yield-checkpoint"


def register(sub) -> None:
    """Add the ``yield`` subcommand to the ``cspace-tol`` sub-parser."""
    from cspace.accuracy import PRESETS

    from ..statistics import METHODS
    y = sub.add_parser(
        "yield", help="statistical yield: defective parts per million and their causes",
        description="Estimate the probability that a part made with the model's parameter "
                    "distributions is defective, by plain Monte Carlo (mc) or by design "
                    "points and importance sampling (is, for rare defects), with a 95 % "
                    "interval, the defect kinds and the parameters that drive them.")
    from .main import add_executor_arguments, add_model_arguments
    add_model_arguments(y)
    y.add_argument("--samples", type=int, default=2000, metavar="N",
                   help="samples of the estimator (default 2000)")
    y.add_argument("--method", choices=METHODS, default="mc",
                   help="mc: plain Monte Carlo (default); is: importance sampling around "
                        "the most probable failure points")
    y.add_argument("--no-search", action="store_true",
                   help="mc only: the samples alone, without the design-point search from "
                        "the failing ones that gives FORM and the contributors (that search "
                        "may cost more tests than the samples)")
    y.add_argument("--cp", type=float, metavar="CP",
                   help="process capability of every parameter whose model entry states no "
                        "distribution (sigma = tol / (3 CP), truncated at the tolerance; "
                        "default 1)")
    y.add_argument("--seed", type=int, default=0, metavar="S", help="random seed (default 0)")
    y.add_argument("--preset", choices=sorted(PRESETS), default="default",
                   help="accuracy preset (default: default)")
    y.add_argument("--deviation", type=float, metavar="D",
                   help="output-deviation threshold d (default: the model's, else the "
                        "library default)")
    add_executor_arguments(y)
    y.add_argument("--no-plots", action="store_true", help="write yield.json only")
    y.add_argument("--resume", action="store_true",
                   help=f"continue a stopped estimate from DIR/{CHECKPOINT} (the same options)")
    y.add_argument("--fresh", action="store_true",
                   help="start over even if DIR holds a stopped estimate (discards it)")
    y.set_defaults(func=cmd_yield)


def cmd_yield(args) -> int:
    from cspace.errors import InputError
    from mechanisms.analysis import resolve_model
    from mechanisms.models import Model

    from .main import check_executor_options, output_dir, writable_dir
    from cspace.argcheck import getseed

    from ..statistics import check_cp
    from ..verify import check_samples
    from .outlock import OutputLock
    model = resolve_model(args.model)
    if not isinstance(model, Model):
        raise InputError(f"yield needs a parametric model (a built-in name or a cspace-model "
                         f"file), got a fixed {type(model).__name__}", name="MODEL",
                         value=args.model)
    # every option checked before the output folder is made
    check_samples(args.samples)
    check_cp(args.cp)
    try:
        getseed(args.seed)
    except InputError:
        raise InputError(f"--seed must be an int >= 0, got {args.seed}", name="--seed",
                         value=args.seed) from None
    check_executor_options(args)
    if getattr(args, "resume", False) and getattr(args, "fresh", False):
        raise InputError("--resume and --fresh exclude each other: --resume continues the "
                         "stopped estimate, --fresh discards it", name="--fresh", value=True)
    if args.no_search and args.method != "mc":
        raise InputError(f"--no-search applies to --method mc only; --method {args.method} "
                         "samples around the design points its search finds", name="--no-search",
                         value=True)
    if args.deviation is not None:
        from cspace.defects import check_deviation
        check_deviation(args.deviation)
    d = _deviation_used(model, args.deviation, args.preset)
    out = output_dir(args.out)
    if getattr(args, "resume", False) and not (out / CHECKPOINT).is_file():
        raise InputError(f"--resume: there is no stopped estimate to continue in {out} (no "
                         f"{CHECKPOINT}); run without --resume to start one", name="--resume",
                         value=str(out / CHECKPOINT))
    lock = OutputLock(writable_dir(out), "cspace-tol yield").acquire()
    try:
        return _run(args, model, d, out)
    finally:
        lock.release()


def _settings(args, model, d) -> dict:
    """What a stopped estimate must share with the run that continues it."""
    from ..checkpoint import model_fingerprint
    return {"model": model.name, "model_sha256": model_fingerprint(model)["sha256"],
            "samples": int(args.samples), "method": args.method, "seed": int(args.seed),
            "cp": None if args.cp is None else float(args.cp), "preset": args.preset,
            "d": float(d), "search": not args.no_search}


def _memo(args, model, d, out):
    """The TestMemo of this run (the stopped estimate's tests with --resume),
    saving itself into DIR/CHECKPOINT."""
    from cspace.errors import InputError
    from cspace.io import atomic_write, dumps

    from ..memo import TestMemo
    ckpt = out / CHECKPOINT
    settings = _settings(args, model, d)
    partial = None
    if ckpt.is_file():
        if getattr(args, "resume", False):
            partial = _read_checkpoint(ckpt, settings)
        elif not getattr(args, "fresh", False):
            raise InputError(f"{out} holds a stopped estimate ({ckpt}); pass --resume to "
                             f"continue it or --fresh to start over", name="--out",
                             value=str(out))

    def save(p):
        atomic_write(ckpt, dumps({"format": FORMAT, "version": 1, "settings": settings,
                                  "partial": p.to_dict()}))

    return TestMemo(1, model.nominal, model.tol, save=save, partial=partial)


def _read_checkpoint(ckpt, settings: dict):
    """The PartialIteration of a stopped estimate whose settings are ``settings``."""
    import json

    from cspace.errors import FileFormatError, InputError

    from ..result import PartialIteration
    try:
        doc = json.loads(ckpt.read_text())
        if not isinstance(doc, dict) or doc.get("format") != FORMAT:
            raise ValueError(f"format must be {FORMAT!r}")
        # a checkpoint from before --no-search searched
        saved = {"search": True, **doc["settings"]}
        partial = PartialIteration.from_dict(doc["partial"])
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise FileFormatError(f"{ckpt} is not a readable yield checkpoint ({e}); remove it or "
                              f"pass --fresh to start over") from None
    diff = [f"{k}: checkpoint {saved.get(k)!r}, given {v!r}" for k, v in settings.items()
            if saved.get(k) != v]
    if diff:
        raise InputError(f"--resume: the stopped estimate in {ckpt} was started with other "
                         f"settings ({'; '.join(diff)}); rerun with its options to continue "
                         f"it, or pass --fresh instead of --resume to start over",
                         name="--resume", value=str(ckpt))
    return partial


def _run(args, model, d, out) -> int:
    from cspace.io import atomic_write, dumps

    from ..executors import make_executor
    from ..statistics import yield_estimate
    from mechanisms.analysis import tolerance_note
    small = tolerance_note(model)
    if small:
        _log(f"warning: {small[1]}")
    memo = _memo(args, model, d, out)
    ckpt = out / CHECKPOINT
    done = len(memo)
    _log(f"{model.name}: {args.method} yield, {args.samples} samples, preset {args.preset}"
         + (f", resumed with {done} finished defect tests" if done else "") + " ...")
    t = time.perf_counter()
    from ..stopping import StopSignals
    from .main import _Terminated
    stop = StopSignals(terminated=_Terminated).install()
    try:
        with make_executor(args.executor, args.workers, args.scheduler) as ex:
            res = yield_estimate(model, args.samples, method=args.method, seed=args.seed,
                                 accuracy=args.preset, d=d, executor=ex, cp=args.cp, memo=memo,
                                 search=not args.no_search)
    except (KeyboardInterrupt, _Terminated) as e:
        term = isinstance(e, _Terminated)
        if len(memo):
            memo.flush()
            kept = (f"its {len(memo)} finished defect tests are kept in {ckpt}: the same "
                    f"command with --resume continues it")
        else:
            kept = "no defect test had finished; rerun the command to estimate"
        _log(f"{'terminated' if term else 'interrupted'}: the estimate was stopped; {kept}")
        return 143 if term else 130
    finally:
        stop.restore()
    _log(f"{model.name}: {res!r} ({time.perf_counter() - t:.1f} s"
         + (f"; {memo.reused} of the checkpoint's {done} finished tests reused" if done else "")
         + ")")
    files = ["yield.json"]
    if not args.no_plots and res.design_points:
        from cspace.plotting import save_figure

        from .plotting import plot_contributors
        save_figure(plot_contributors(res), out / "contributors.png")
        files.append("contributors.png")
    doc = {"model": model.name, "units": model.units, "preset": args.preset,
           "cp": 1.0 if args.cp is None else float(args.cp), "d": d,
           "parameters": _parameters(model, args.cp), **res.to_dict(), "files": files,
           "vector_units": "design points' x, failing parts and every parameter vector "
                           "are in parameters[i].unit (the model's length unit, rad for an "
                           "angle); z is in standard normal units"}
    atomic_write(out / "yield.json", dumps(doc))
    ckpt.unlink(missing_ok=True)
    _log(f"{model.name}: wrote {', '.join(files)} to {out}")
    return 0


def _deviation_used(model, d, accuracy=None):
    """The output-deviation threshold the estimate uses: ``d``, else the
    model's ``deviation``, else :func:`cspace.defects.default_deviation`
    (``5 t / L``, t the largest tolerance of a parameter that moves a contact,
    L the smallest pair's characteristic length) of the nominal reference at
    ``accuracy``."""
    from cspace.defects import reference
    if d is None:
        d = getattr(model, "deviation", None)
    if d is not None:
        return float(d)
    # the default reads which parameters move a contact: the nominal C-spaces
    return float(reference(model, accuracy).d)


def _parameters(model, cp=None) -> list:
    """Each parameter's name, unit of its values in ``yield.json`` (rad for an
    angle), nominal, tolerance and distribution (the default's when it states
    none, of Cp ``cp``)."""
    from mechanisms.models.base import DEFAULT_DISTRIBUTION, Distribution
    dflt = DEFAULT_DISTRIBUTION if cp is None else Distribution("truncated_normal", cp=cp)
    return [{"name": p.name, "unit": u, "nominal": float(p.nominal), "tol": float(p.tol),
             "distribution": (p.distribution or dflt).to_dict(),
             "distribution_stated": p.distribution is not None}
            for p, u in zip(model.parameters, model.param_units)]


def _log(msg: str):
    print(msg, file=sys.stderr, flush=True)
