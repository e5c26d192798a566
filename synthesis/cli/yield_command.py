"""The ``yield`` subcommand of the command line: statistical yield of a model.

yield MODEL --out DIR [--samples N] [--method mc|is] [--cp CP] [--seed S]
      [--preset P] [--deviation D] [--executor process|serial|dask] [--workers N]
      [--scheduler ADDR] [--no-plots]
    Estimates the probability that a part made with the model's distributions
    (each parameter's ``distribution``, default a normal of Cp 1 truncated at
    its tolerance) is defective (:func:`synthesis.statistics.yield_estimate`),
    and writes ``yield.json`` and ``contributors.png``.  ``yield.json`` also
    holds what reads or reruns it: the threshold ``d`` used, the Cp used,
    each parameter's unit and distribution (every vector, design points'
    ``x`` included, is in these units: rad for an angle).  Every option is
    checked before DIR is made.  Exit status 0, 2 bad input, 130 stopped by
    SIGINT (Ctrl-C), 143 stopped by SIGTERM (the pool shut down, nothing
    written; a stopped estimate cannot be resumed: rerun it).
"""

from __future__ import annotations

import sys
import time

__all__ = ["register", "cmd_yield"]


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
    y.set_defaults(func=cmd_yield)


def cmd_yield(args) -> int:
    from cspace.errors import InputError
    from cspace.io import atomic_write, dumps
    from mechanisms.analysis import resolve_model
    from mechanisms.models import Model

    from .main import output_dir, writable_dir
    from cspace.argcheck import getseed

    from ..executors import check_executor_kind, make_executor
    from ..statistics import check_cp, yield_estimate
    from ..verify import check_samples
    model = resolve_model(args.model)
    if not isinstance(model, Model):
        raise InputError(f"yield needs a parametric model (a built-in name or a cspace-model "
                         f"file), got a fixed {type(model).__name__}", name="MODEL",
                         value=args.model)
    # every option checked before the output folder is made
    check_samples(args.samples)
    check_cp(args.cp)
    getseed(args.seed)
    check_executor_kind(args.executor, args.workers)
    if args.deviation is not None:
        from cspace.defects import check_deviation
        check_deviation(args.deviation)
    d = _deviation_used(model, args.deviation, args.preset)
    out = writable_dir(output_dir(args.out))
    _log(f"{model.name}: {args.method} yield, {args.samples} samples, preset {args.preset} ...")
    t = time.perf_counter()
    from ..stopping import StopSignals
    from .main import _Terminated
    stop = StopSignals(terminated=_Terminated).install()
    try:
        with make_executor(args.executor, args.workers, args.scheduler) as ex:
            res = yield_estimate(model, args.samples, method=args.method, seed=args.seed,
                                 accuracy=args.preset, d=d, executor=ex, cp=args.cp)
    except (KeyboardInterrupt, _Terminated) as e:
        term = isinstance(e, _Terminated)
        _log(f"{'terminated' if term else 'interrupted'}: the estimate was stopped and "
             f"nothing was written to {out}; rerun the command to estimate again")
        return 143 if term else 130
    finally:
        stop.restore()
    _log(f"{model.name}: {res!r} ({time.perf_counter() - t:.1f} s)")
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
