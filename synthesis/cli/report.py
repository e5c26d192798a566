"""The output folder of a synthesis run: the report, the geometry and the
figures (contact zones before and after, [Tolerance synthesis] Figs. 3, 7, 9,
and the defect count per iteration), which :mod:`synthesis.cli.plotting` draws.

Output folder (``write_outputs``)
--------------------------------
``report.json``
    :meth:`SynthesisResult.to_dict` plus the model units, the Monte Carlo
    verification (when run) and the list of files written.  ``changes``,
    ``changed`` and ``shrunk`` give each parameter's values in its own unit
    (``parameter_units``: degrees for a model-file entry ``"unit": "deg"``);
    the vectors ``initial``, ``final`` and ``history`` are in the library's
    units (``vector_units``: angles in rad), as ``checkpoint.json`` holds them.
``report.md``
    The same for a reader: status and why, e against the tolerances, the
    changed dimensions, defects per iteration, zone overlaps against defects,
    the Monte Carlo figures and how to reproduce the run
    (:func:`markdown_report`).
``pair.json`` / ``pair_initial.json``
    The final and the initial nominal geometry (``cspace-pair`` or
    ``cspace-assembly``).
``model.json`` / ``model_initial.json``
    The final and the initial design as ``cspace-model`` files, which
    ``analyze``, ``synthesize`` and ``export-dxf`` accept: for a model read from
    a file its own document with the new values, for a built-in model a
    document naming it (``"builtin"``) with the values.  Not written for a
    model made in Python (its geometry is code): ``report.md`` then shows the
    Python call that repeats the run instead of the command line.
``checkpoint.json``
    Listed in the report when the folder holds it: the command line writes it
    during the run; ``write_outputs`` does not.
``zones_before{_pair}.png``, ``zones_after{_pair}.png``, ``zones{_pair}.png``
    The zones of the operating channel of the initial and final designs, and
    both side by side.
``parts.png``
    The parts before (dashed) and after (solid), the changes magnified when
    they are too small to see (the factor is in the title).
``changes.png``
    Per parameter: the nominal shift and the tolerance cut, in units of the
    initial tolerance.
``failures{_pair}.png``
    Where defective vectors removed during the run fail (re-tested against the
    initial design; at most :data:`MAX_FAILURE_MARKS`), when the caller passes
    them (``removed``).
``defects.png``
    Defective check-list vectors per iteration.

Zone overlaps and defects
-------------------------
The zone plots count *zone overlaps*: places where the zone bands (every
position a contact curve can take over the tolerance box) of the two curves
bounding a channel overlap.  They are a conservative bound and usually remain
after convergence.  *Defects* are tested variants (check-list vectors) whose
motion jams, changes contact sequence or deviates by more than d; convergence
means no defect is left.  ``docs/synthesis.md`` ("Zone overlaps") explains the
difference.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from cspace.errors import InputError

from .plotting import (plot_changes, plot_defect_history, plot_parts_before_after,
                       plot_zones_before_after, separate_labels)

__all__ = ["write_outputs", "complete_zones", "markdown_report", "reproduce_command",
           "reproduce_python", "deviation_scales", "in_declared_units",
           "operating_point", "verification_verdict", "MAX_FAILURE_MARKS"]

#: Removed defective vectors re-tested to mark where they fail (failures.png).
MAX_FAILURE_MARKS = 12


def reproduce_command(result, model_file: str = "model_initial.json", out: str = "again",
                      verification=None) -> str:
    """The ``cspace-tol synthesize`` command that repeats the run from the
    initial model file written beside the report.  That file states the
    follower start the run used (:func:`write_outputs`), a guessed one too, so
    the command needs no ``--accept-start``."""
    acc = result.accuracy.get("name", "default")
    cmd = [f"cspace-tol synthesize {model_file} --out {out}"]
    if acc in ("fast", "default", "precise"):
        cmd.append(f"--preset {acc}")
    cmd.append(f"--patience {result.patience}")
    if not result.two_sided:
        cmd.append("--no-two-sided")
    cmd.append(f"--deviation {result.d!r}")
    if getattr(result, "removal", "lp") != "lp":
        cmd.append(f"--removal {result.removal}")
    if result.status.name == "MAX_ITER":
        cmd.append(f"--max-iter {result.nit}")
    t = getattr(result, "target", None)
    if t is not None:
        # the estimates' seed is --seed, as --verify's
        cmd.append(f"--target-yield {t['target']!r} --yield-samples {t['samples']} "
                   f"--yield-method {t['method']}")
        if t.get("cp") is not None:
            cmd.append(f"--cp {t['cp']!r}")
    if verification:
        v = next(iter(verification.values()))
        cmd.append(f"--verify {v.n} --seed {v.seed}")
    elif t is not None:
        cmd.append(f"--seed {t.get('seed', 0)}")
    return " ".join(cmd)


def reproduce_python(result, verification=None, operating=None) -> str:
    """The Python calls that repeat the run from the initial design (a model
    made in Python, which no model file can hold): the settings of
    :func:`reproduce_command` as :func:`synthesis.synthesize` arguments, and
    ``accept_start=True`` when ``operating`` (:func:`operating_point`) shows
    a follower start the library guessed among several free intervals."""
    acc = result.accuracy.get("name", "default")
    args = ["model"]
    if acc in ("fast", "default", "precise"):
        args.append(repr(acc))
    args.append(f"d={result.d!r}")
    args.append(f"patience={result.patience}")
    if not result.two_sided:
        args.append("two_sided=False")
    if getattr(result, "removal", "lp") != "lp":
        args.append(f"removal={result.removal!r}")
    if result.status.name == "MAX_ITER":
        args.append(f"max_iter={result.nit}")
    if any(o.get("start_source") == "guessed" and len(o.get("free_intervals") or ()) > 1
           for o in operating or ()):
        args.append("accept_start=True")
    t = getattr(result, "target", None)
    if t is not None:
        args.append(f"target_yield=YieldTarget({t['target']!r}, samples={t['samples']}, "
                    f"method={t['method']!r}, cp={t.get('cp')!r}, seed={t.get('seed', 0)})")
    lines = ["from synthesis import synthesize", f"result = synthesize({', '.join(args)})"]
    if t is not None:
        lines.insert(1, "from synthesis.target import YieldTarget")
    if verification:
        # both boxes against the initial design, as the command line checks them
        acc_arg = f"accuracy={acc!r}, " if acc in ("fast", "default", "precise") else ""
        lines[0] = "from synthesis import monte_carlo, synthesize"
        lines.append("final = model.with_nominal(result.nominal).with_tolerances(result.tol)")
        for which, v in verification.items():
            box = "model" if which == "initial" else "final"
            lines.append(f"check_{which} = monte_carlo({box}, {v.n}, seed={v.seed}, "
                         f"{acc_arg}d=result.d, intent=model)")
    return "\n".join(lines)


def deviation_scales(model) -> tuple:
    """Per pair of ``model`` (its initial design), what the deviation
    threshold d measures: ``(pair name, follower unit, L)``, L the pair's
    characteristic length for a sliding follower (d is a slide over L) and
    None for a rotating one (d is an output angle in rad)."""
    from mechanisms.analysis import follower_unit, pairs_of
    out = []
    for p in pairs_of(model):
        unit = follower_unit(p)
        out.append((p.name, unit, None if unit == "rad" else float(p.char_length)))
    return tuple(out)


def _deviation_text(d: float, scales) -> str:
    """d in the follower units of each pair (:func:`deviation_scales`)."""
    parts = []
    for name, unit, L in scales or ():
        if L is None:
            parts.append(f"{name!r}: an output angle of {d:.4g} rad "
                         f"({math.degrees(d):.4g} deg)")
        else:
            parts.append(f"{name!r}: a slide of {d * L:.4g} {unit} (d times the pair's "
                         f"characteristic length L = {L:.4g} {unit})")
    return ("; for " + ", ".join(parts)) if parts else ""


def verification_verdict(result, verification) -> dict | None:
    """Whether the final box passed ``--verify``'s Monte Carlo check: None
    when no check of the final box ran, else ``{"passed", "defective",
    "samples", "text"}``.

    A worst-case run (no target yield) passes only with no defective sample:
    its box is meant to hold no defective variant at all.  A target-yield run
    lets some fail: it passes unless the check's failure rate is clearly above
    the target (the lower end of its 95 % interval above ``1 - Y``)."""
    v = (verification or {}).get("final")
    if v is None:
        return None
    k, n = int(v.n_defective), int(v.n)
    t = getattr(result, "target", None)
    if t is None:
        passed = k == 0
        allowed = "none allowed: the synthesized box is meant to hold no defective variant"
    else:
        from ..statistics import clopper_pearson
        lo, _ = clopper_pearson(k, n)
        passed = lo <= t["ppm"] * 1e-6
        allowed = (f"the target allows {t['ppm']:.6g} ppm; the lower end of the check's "
                   f"95 % interval is {1e6 * lo:.6g} ppm")
    text = (f"the final box {'passed' if passed else 'FAILED'} its Monte Carlo check: {k} of "
            f"{n} samples defective ({allowed})")
    if not passed:
        status = getattr(getattr(result, "status", None), "name", "")
        if status in ("CONVERGED", "TARGET_YIELD"):
            text += ("; the result must not be trusted as it is: the check list missed "
                     "defects the samples found (run again with a finer --preset, or check "
                     "the defective samples: report.json, verification.final.first_defective)")
        else:
            # the run stopped with defects it knew of: the samples only confirm them
            text += (f"; the run ended {status or 'early'} with defects left in its check "
                     f"list, which the samples confirm: the box is not a result (see the "
                     f"run's message for why it stopped; the defective samples are in "
                     f"report.json, verification.final.first_defective)")
    return {"passed": passed, "defective": k, "samples": n, "text": text}


def operating_point(model, result, accuracy=None, ref=None) -> list | None:
    """Per pair, the operating point the run tested every variant at: the
    follower start (stated in the model, or guessed by the library when it
    states none), the drive and the C-space window, from the initial design's
    reference (``ref``, else :func:`synthesis.executors.cached_reference`, which
    the synthesis loop of this process filled).  A list of dicts (the
    ``operating_point`` of ``report.json``); None when the reference cannot be
    built."""
    from cspace.accuracy import PRESETS
    from cspace.errors import CSpaceError
    from cspace.geometry import Rotation
    from mechanisms.analysis import follower_unit, operating_point_notes

    from ..accuracy import as_synthesis_accuracy
    from ..executors import cached_reference
    if ref is None:
        if accuracy is None:
            name = (getattr(result, "accuracy", None) or {}).get("name")
            accuracy = name if name in PRESETS else None
        intent = model.with_nominal(result.initial_nominal).with_tolerances(result.initial_tol)
        try:
            ref = cached_reference(intent, as_synthesis_accuracy(accuracy), result.d)
        except (CSpaceError, ValueError):
            return None
    stated = getattr(model, "q2_start", None) is not None
    choices = tuple(ref.start_choices) or (None,) * len(ref.spaces)
    try:
        notes = operating_point_notes(ref.spaces, ref.sims, ref.start_choices)
    except (CSpaceError, ValueError):
        notes = []
    out = []
    for cs, start, ch in zip(ref.spaces, ref.starts, choices):
        du = "rad" if isinstance(cs.pair.driver.axis, Rotation) else cs.pair.units
        fu = follower_unit(cs.pair)
        o = {"pair": cs.pair.name, "q1_start": float(start[0]), "q2_start": float(start[1]),
             "start_source": "stated" if stated or ch is None else "guessed",
             "drive": [float(ref.drive[0]), float(ref.drive[1])],
             "drive_source": "stated" if getattr(model, "drive", None) is not None
             else "default",
             "window": [float(x) for x in cs.window],
             "window_source": "stated" if getattr(model, "window", None) is not None
             else "default",
             "driver_unit": du, "follower_unit": fu}
        if o["start_source"] == "guessed":
            o["free_intervals"] = [[float(a), float(b)] for a, b in ch.intervals]
        # what the log said of this pair's operating point (a warning, or a
        # note such as a start in the play of the channel)
        o["notes"] = [{"warning": bool(w), "text": t} for w, t in notes
                      if t.startswith(f"pair {cs.pair.name!r}")]
        out.append(o)
    return out


def _operating_lines(operating) -> list:
    """``report.md``'s section on the operating point: per pair the follower
    start (stated or guessed), the drive and the window, with units, and what
    the log noted of it."""
    if not operating:
        return []
    lines = ["## Operating point", "",
             "| pair | follower start q2 | at driver q1 | start | drive | window |",
             "|---|---:|---:|---|---|---|"]
    for o in operating:
        du, fu = o["driver_unit"], o["follower_unit"]
        w = o["window"]
        how = o["start_source"]
        if how == "guessed":
            n = len(o.get("free_intervals") or ())
            how = (f"guessed: the middle of the widest of {n} free interval(s)" if n > 1 else
                   "guessed: the middle of the only free interval")
        lines.append(f"| {o['pair']} | {o['q2_start']:.6g} {fu} | {o['q1_start']:.6g} {du} | "
                     f"{how} | {o['drive'][0]:.6g} to {o['drive'][1]:.6g} {du} "
                     f"({o['drive_source']}) | q1 {w[0]:.6g} to {w[1]:.6g} {du}, q2 "
                     f"{w[2]:.6g} to {w[3]:.6g} {fu} ({o['window_source']}) |")
    lines.append("")
    for o in operating:
        for n in o.get("notes") or ():
            lines.append(("- **Warning:** " if n["warning"] else "- ") + n["text"] + ".")
    if any(o.get("notes") for o in operating):
        lines.append("")
    if any(o["start_source"] == "guessed" for o in operating):
        lines += ["The model states no follower start: the run used the start above, which "
                  "the library chose (with several free intervals only with "
                  "`--accept-start`). `model_initial.json` states it (`q2_start`), so a run "
                  "from it is the same mechanism and needs no `--accept-start`.", ""]
    return lines


def markdown_report(result, *, verification=None, files=(), command=None,
                    scales=None, operating=None, previous=None, failures=None) -> str:
    """``report.md``: a short summary of a synthesis run for a reader.

    Parameters
    ----------
    result : SynthesisResult
    verification : dict of MonteCarloResult, optional
        ``{"initial": ..., "final": ...}`` when ``--verify`` ran.
    files : sequence of str
        The files of the output folder.
    command : str, optional
        The command line that ran (shown under "Reproduce").
    scales : tuple, optional
        :func:`deviation_scales` of the model: d is then also stated in each
        pair's follower units.
    operating : list, optional
        :func:`operating_point`: the start, drive and window of each pair.
    previous : str, optional
        The subfolder the outputs of an earlier finished run in this folder
        were moved to.
    """
    defects = result.defects_per_iteration()
    ch = result.changes()
    shifted = [nm for nm, c in ch.items() if c["delta"] != 0]
    cut = [nm for nm, c in ch.items() if c["tol_final"] != c["tol_initial"]]
    lines = _status_lines(result, defects)
    verdict = verification_verdict(result, verification)
    if verdict is not None and not verdict["passed"]:
        lines += [f"**Warning: {verdict['text'][0].upper() + verdict['text'][1:]}.**", ""]
    if previous:
        lines += [f"This folder held the outputs of an earlier run: they were moved to "
                  f"`{previous}/` before this run wrote its own.", ""]
    lines += _tolerance_lines(result, ch, shifted, cut, scales)
    lines += _operating_lines(operating)
    lines += _target_lines(result)
    lines += _changed_lines(result, ch, shifted, cut)
    lines += _history_lines(result)
    lines += _failure_lines(result, failures)
    lines += [] if result.interrupted else _overlap_lines(result, defects)
    lines += _verification_lines(verification, verdict)
    if getattr(result, "sampled", ()):
        k = len(result.sampled)
        lines += [f"The run went on after a failed Monte Carlo check of a converged box: "
                  f"{k} defective sample(s), each reduced to the parameters its defect needs, "
                  f"joined the check list (`sampled` in report.json; `--verify-rounds`), and "
                  f"the table above is the check of the box that followed."
                  + (" That check failed too, and no round of `--verify-rounds` was left to go "
                     "on with (a larger `--verify-rounds` goes on)."
                     if verdict is not None and not verdict["passed"]
                     and getattr(result, "status", None) is not None
                     and result.status.name == "CONVERGED" else ""), ""]
    lines += _reproduce_lines(result, verification, command, files, operating)
    if files:
        lines += ["## Files", ""] + [f"- `{f}`" for f in files] + [""]
    return "\n".join(lines)


def _status_lines(result, defects) -> list:
    """``report.md``'s title and status: why the run stopped, how to resume an
    interrupted one, and the defects, tests and time per iteration."""
    lines = [f"# Tolerance synthesis of {result.model}", ""]
    lines += [f"**Status: {result.status.name}** after {result.nit} iteration(s). "
              f"{result.message[:1].upper() + result.message[1:]}.", ""]
    if result.interrupted and result.interrupted.get("after_synthesis"):
        it = result.interrupted
        lines += [f"The synthesis itself had ended ({it['after_synthesis']}); the run was "
                  f"stopped during {it['phase']}. The design below is its final design. Run "
                  f"the same command again with `--resume` to finish "
                  f"{it['phase']} and write the complete report (the synthesis is not "
                  f"repeated).", ""]
    elif result.interrupted:
        it = result.interrupted
        lines += [f"The design below is the one iteration {it['iteration']} was testing. "
                  f"Run the same command again with `--resume` to continue from the tests "
                  f"kept in `checkpoint.json`: the result is the uninterrupted run's. The "
                  f"zone plots are written when the run ends.", ""]
    if defects:
        lines += [f"Defective check-list vectors per iteration: "
                  f"{', '.join(str(n) for n in defects)}; "
                  f"{sum(h.tests for h in result.history)} defect tests in "
                  f"{sum(h.times.get('total', 0.0) for h in result.history):.0f} s.", ""]
    return lines


def _tolerance_lines(result, ch, shifted, cut, scales=None) -> list:
    """``report.md``'s section on the result against the tolerances: e against
    the largest and smallest initial tolerance, the count of shifts and cuts,
    the smallest tolerance kept and the run's settings."""
    u = result.units
    # e and the tolerances it is set against: the lengths' (angles apart)
    lengths = np.array([result.unit_of(i) == u for i in range(len(result.names))], dtype=bool)
    t0 = np.asarray(result.initial_tol)[lengths] if len(lengths) else result.initial_tol
    tmax = float(np.max(t0)) if len(t0) else 0.0
    tmin = float(np.min(t0[t0 > 0])) if np.any(t0 > 0) else 0.0
    lines = ["## Result against the tolerances", ""]
    over = " (over the lengths)" if not lengths.all() else ""
    if tmax > 0:
        lines += [f"- e = max |u0' - u0|{over} = {result.e:.4g} {u}: {result.e / tmax:.2f} x the "
                  f"largest initial tolerance ({tmax:.4g} {u})"
                  + (f", {result.e / tmin:.2f} x the smallest ({tmin:.4g} {u})"
                     if tmin != tmax else "") + "."]
    if result.e_angle is not None:
        lines += [f"- The largest shift of an angle: {result.e_angle:.4g} rad "
                  f"({math.degrees(result.e_angle):.4g} deg)."]
    lines += [f"- {len(shifted)} of {len(ch)} nominal dimensions shifted, {len(cut)} "
              f"tolerance(s) cut."]
    shares = {nm: ch[nm]["tol_final"] / ch[nm]["tol_initial"] for nm in cut
              if ch[nm]["tol_initial"] > 0}
    if shares:
        least = min(shares.values())
        # every parameter cut that far (several often are, at the --min-keep floor)
        at = [nm for nm in cut if nm in shares and shares[nm] <= least * (1 + 1e-9)]
        lines += [f"- Smallest tolerance kept: {100 * least:.0f} % of its initial value "
                  f"({', '.join(at)})."]
    lines += [f"- Deviation threshold d = {result.d:.4g} (C-space metric: rad, or slide / "
              f"characteristic length){_deviation_text(result.d, scales)}; accuracy preset "
              f"`{result.accuracy.get('name', '?')}`; patience {result.patience}; two-sided "
              f"{'on' if result.two_sided else 'off'}.", ""]
    return lines


def _changed_lines(result, ch, shifted, cut) -> list:
    """``report.md``'s table of the changed dimensions, with the defect that
    required each change."""
    u = result.units
    lines = ["## Changed dimensions", ""]
    if not (shifted or cut):
        return lines + ["No dimension or tolerance changed.", ""]
    why = _required_by(result)
    units = [result.unit_of(i) for i in range(len(result.names))]
    if all(x == u for x in units):
        lines += [f"| parameter | initial [{u}] | final [{u}] | delta [{u}] | "
                  f"tolerance before [{u}] | tolerance after [{u}] | required by |",
                  "|---|---:|---:|---:|---:|---:|---|"]
        unit_col = {}
    else:
        # parameters in several units (lengths and angles): a unit column
        lines += ["| parameter | unit | initial | final | delta | tolerance before | "
                  "tolerance after | required by |", "|---|---|---:|---:|---:|---:|---:|---|"]
        unit_col = dict(zip(result.names, units))
    for nm, c in ch.items():
        if nm not in shifted and nm not in cut:
            continue
        col = f" {unit_col[nm]} |" if unit_col else ""
        lines.append(f"| {nm} |{col} {c['initial']:.6g} | {c['final']:.6g} | "
                     f"{c['delta']:+.4g} | {c['tol_initial']:.4g} | {c['tol_final']:.4g} | "
                     f"{why.get(nm, '')} |")
    return lines + ["", "\"Required by\" names, for every shift and cut, the defect that "
                    "required it: the check-list vector (or its mirror through the nominal), "
                    "the pair, the kind of defect and the driver position q1 where the first "
                    "defective point found on its segment fails (`report.json`, "
                    "`history[].required`; q1 in the driver's unit along the whole drive, "
                    "past one turn on a drive of several: the C-space plots fold it into "
                    "one turn, and `failures.png` marks where re-tested defects fail).  "
                    "\"Defective at both sides\" marks a vector that "
                    "is defective at its mirror through the nominal too: no shift of the "
                    "nominal clears both, which is why a cut rather than a shift.", ""]


def _history_lines(result) -> list:
    """``report.md``'s table of the defects, changes, tests and time per
    iteration (nothing for a run without iterations)."""
    if not result.history:
        return []
    lines = ["## Defects per iteration", "",
             "| iteration | check list | defective | reasons | also at the mirror | "
             "zone overlaps | shifted | cuts | tests | time [s] |",
             "|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|"]
    for h in result.history:
        reasons = ", ".join(f"{k.lower()} {v}" for k, v in
                            sorted(h.reasons.items(), key=lambda kv: -kv[1])) or "-"
        lines.append(f"| {h.iteration} | {h.counts.get('checklist', 0)} | {h.n_defects} | "
                     f"{reasons} | {h.counts.get('two_sided', '-')} | {h.overlaps} | "
                     f"{int((h.shift != 0).sum())} | {len(h.shrinks)} | {h.tests} | "
                     f"{h.times.get('total', 0.0):.1f} |")
    return lines + [""]


def _overlap_lines(result, defects) -> list:
    """``report.md``'s note that zone overlaps are not defects, with the final
    design's counts of both."""
    return ["## Zone overlaps are not defects", "",
            f"The final design has {len(result.overlaps)} zone overlap(s) and "
            f"{defects[-1] if defects else 'no tested'} defective vector(s). A zone overlap "
            "is where the zone bands (all positions a contact curve takes over the tolerance "
            "box) of the two curves bounding a channel overlap: a conservative bound that "
            "some variant may close the channel. A defect is a tested variant whose motion "
            "jams, changes contact sequence or deviates by more than d. Convergence means no "
            "defect is left; overlaps usually remain (docs/synthesis.md, \"Zone overlaps\").",
            ""]


def _verification_lines(verification, verdict=None) -> list:
    """``report.md``'s Monte Carlo table and the verdict on the final box
    (nothing when ``--verify`` did not run)."""
    if not verification:
        return []
    lines = ["## Monte Carlo check", "",
             "| box | samples | of which corners | defective | rate | seed |",
             "|---|---:|---:|---:|---:|---:|"]
    for k, v in verification.items():
        lines.append(f"| {k} | {v.n} | {v.n_corners} | {v.n_defective} | "
                     f"{100 * v.rate:.2f} % | {v.seed} |")
    lines += ["", "Both boxes are tested against the initial design, as the synthesis "
              "tested them; half the samples are box corners, half interior points.", ""]
    if verdict is not None:
        lines += [f"Verdict: {verdict['text']}.", ""]
    final = verification.get("final")
    msgs = getattr(final, "messages", ()) if final is not None else ()
    if msgs:
        lines += ["Where the first defective samples of the final box fail (their vectors: "
                  "report.json, verification.final.first_defective):", ""]
        lines += [f"- sample {i}: {m}" for i, m in zip(final.defective, msgs)] + [""]
    return lines


def _reproduce_lines(result, verification, command, files=(), operating=None) -> list:
    """``report.md``'s section on reproducing the run: the command from the
    folder's files (or, when ``files`` shows no ``model_initial.json``, the
    call from Python), the command that ran, and the note on workers."""
    if files and "model_initial.json" not in files:
        lines = ["## Reproduce", "",
                 f"The model {result.model!r} was made in Python (its geometry is code), so "
                 "this folder holds no model file to start from. With the same model object "
                 "(its initial design):", "", "```python",
                 reproduce_python(result, verification=verification, operating=operating),
                 "```", ""]
    else:
        lines = ["## Reproduce", "", "From the files in this folder:", "", "```sh",
                 reproduce_command(result, verification=verification), "```", ""]
    if command:
        lines += ["The command that ran:", "", "```sh", command, "```", ""]
    return lines + ["Results do not depend on the number of workers or the executor.", ""]

def _target_lines(result) -> list:
    """``report.md``'s section on a target-yield run: the target, the estimate
    of the final design and the worst-case status beside it."""
    if result.target is None:
        return []
    from ..target import ppm_text
    t = result.target
    ye = result.yield_estimate
    lines = ["## Target yield", "",
             f"- Target: yield {t['target']:.6g} (at most {ppm_text(t['ppm'])} ppm defective), "
             f"estimated by {t['method']} with {t['samples']} samples (seed {t['seed']}, Cp "
             f"{t['cp'] if t['cp'] is not None else 1:g} where the model states no "
             f"distribution), every part against the initial design."]
    if ye is not None:
        lo, hi = (ppm_text(v) for v in ye["ci_ppm"])
        lines += [f"- Estimated at the final design: {ppm_text(ye['ppm'])} ppm defective "
                  f"({ye['failures']}/{ye['samples']}; 95 % interval [{lo}, {hi}] "
                  f"ppm): target {'met' if ye['met'] else 'not met'}."]
        if ye.get("plain"):
            lines += ["- Importance sampling found no failure region to sample around at the "
                      "final design, so the estimate drew plain Monte Carlo samples (exact "
                      "interval): more samples narrow it."]
        if ye.get("check"):
            c = ye["check"]
            lines += [f"- Independent check (seed {c['seed']}): {ppm_text(c['ppm'])} ppm "
                      f"(95 % interval [{ppm_text(c['ci_ppm'][0])}, "
                      f"{ppm_text(c['ci_ppm'][1])}] ppm)"
                      + (f": unconfirmed, {ye['unconfirmed']}." if ye.get("unconfirmed")
                         else ": agrees.")]
    if result.history:
        left = result.history[-1].n_defects
        lines += [f"- Worst case: {left} defective check-list vector(s) left"
                  + (" (improbable corners the target lets stay)." if left else ".")]
    estimated = [h for h in result.history if h.yield_estimate]
    if estimated:
        lines += ["", "| iteration | defective check-list vectors | estimated ppm | 95 % "
                      "interval (ppm) |", "|---:|---:|---:|---|"]
        for h in estimated:
            y = h.yield_estimate
            lines.append(f"| {h.iteration} | {h.n_defects} | {ppm_text(y['ppm'])} | "
                         f"[{ppm_text(y['ci_ppm'][0])}, {ppm_text(y['ci_ppm'][1])}] |")
    return lines + [""]


def _defect_text(r: dict, iteration=None) -> str:
    """``vector 12 (mirror; pair 0, jam, q1 = 0.51)``: a defect that required a change
    (with ``removal="lp"`` also the margin that bound it, and the iteration of
    its check list when it is an earlier one)."""
    bits = []
    if r.get("mirror"):
        bits.append("at its mirror")
    if r.get("pair") is not None:
        bits.append(f"pair {r['pair']}")
    if r.get("kind"):
        bits.append(" & ".join(r["kind"]))
    if r.get("q1") is not None:
        bits.append(f"q1 = {r['q1']:.4g}")
    if r.get("margin"):
        bits.append(f"linearised {r['margin']} margin")
    if r.get("both_sides"):
        bits.append("defective at both sides: the vector and its mirror")
    of = (f" of iteration {r['iteration']}" if r.get("iteration") is not None
          and r.get("iteration") != iteration else "")
    return f"vector {r['vector']}{of}" + (f" ({', '.join(bits)})" if bits else "")


def _required_by(result) -> dict:
    """Per parameter: the defect that required each shift and cut (pair, kind,
    place in the motion, check-list vector), or for records without that, the
    iterations whose defects shifted it and the vector each cut cured."""
    if all(h.required or (not np.any(h.shift != 0) and not h.shrinks)
           for h in result.history):
        out: dict = {}
        for h in result.history:
            for r in h.required:
                out.setdefault(r["parameter"], []).append(
                    f"{r['change']} in iteration {h.iteration}: {_defect_text(r, h.iteration)}")
        return {k: "; ".join(v) for k, v in out.items()}
    out = {}
    shifts: dict = {}
    for h in result.history:
        for i in range(len(result.names)):
            if h.shift[i] != 0:
                shifts.setdefault(result.names[i], []).append(h)
    for nm, hs in shifts.items():
        its = ", ".join(str(h.iteration) for h in hs)
        ds = ", ".join(str(h.n_defects) for h in hs)
        out[nm] = [f"shift{'s' if len(hs) > 1 else ''} in iteration{'s' if len(hs) > 1 else ''} "
                   f"{its} ({ds} defective)"]
    for h in result.history:
        for sh in h.shrinks:
            nm = sh.get("parameter")
            if nm is not None:
                v = sh.get("vector")
                out.setdefault(nm, []).append(
                    f"cut in iteration {h.iteration}"
                    + (f" for check-list vector {v}" if v is not None else "")
                    + (f" ({sh['reason']})" if sh.get("reason") else ""))
    return {k: "; ".join(v) for k, v in out.items()}


def _failure_lines(result, failures) -> list:
    """``report.md``'s list of the defects marked in ``failures.png`` (its
    labels r0, r1, ...): why and where each fails, re-tested against the
    initial design."""
    from cspace.defects import main_reason
    if not failures:
        return []
    names = [cs.pair.name for cs in (result.spaces_initial or ())]
    lines = ["## Where the marked defects fail (`failures.png`)", "",
             f"The first {len(failures)} defective vectors the run removed, re-tested "
             f"against the initial design with the full test: the marks of "
             f"`failures.png` (a jam where the drive jams).", "",
             "| mark | reason | pair | what the full test found |", "|---|---|---|---|"]
    for k, r in enumerate(failures):
        if not getattr(r, "defective", False):
            lines.append(f"| r{k} | healthy now | | |")
            continue
        main = main_reason(r.reasons)
        why = main.name.lower() if main is not None else "invalid"
        pair = ""
        if r.where:
            i = int(r.where[0])
            pair = names[i] if i < len(names) else str(i)
        msg = str(r.message).replace("|", "/")
        lines.append(f"| r{k} | {why} | {pair} | {msg} |")
    return lines + [""]


def failure_retests(result, model, removed, accuracy, executor) -> list:
    """The full defect tests of ``failures.png`` (the first
    :data:`MAX_FAILURE_MARKS` of ``removed``, against the initial design) as
    tasks of ``executor`` (a synthesis's pool, whose workers hold the initial
    design's reference): pass them to :func:`write_outputs` (``failures``)."""
    from ..accuracy import as_synthesis_accuracy
    from ..executors import defect_task, run_ordered
    intent = model.with_nominal(result.initial_nominal).with_tolerances(result.initial_tol)
    acc = as_synthesis_accuracy(accuracy)
    return run_ordered(executor, defect_task, [(intent, np.asarray(u, dtype=float), acc,
                                                result.d)
                                               for u in list(removed)[:MAX_FAILURE_MARKS]])


def _failure_plots(result, model, out, suffixes, removed, accuracy, failures=None):
    """Re-test up to MAX_FAILURE_MARKS removed defective vectors against the
    initial design (or take ``failures``, :func:`failure_retests`) and mark
    where each fails on the initial C-space."""
    from cspace.plotting import plot_failures, save_figure
    picked = list(removed)[:MAX_FAILURE_MARKS]
    if failures is None or len(failures) != len(picked):
        # here, in this process (one reference for every re-test)
        from ..executors import SerialExecutor
        failures = failure_retests(result, model, removed, accuracy, SerialExecutor())
    results = list(failures)
    written = []
    for i, (cs, sfx) in enumerate(zip(result.spaces_initial, suffixes)):
        ax = plot_failures(cs, results, pair_index=i, labels=[f"r{k}" for k in
                                                                range(len(results))],
                           title=f"{cs.pair.name}: where {len(picked)} removed defective "
                                 f"vector(s) fail (re-tested)")
        # labels of nearby marks apart, as they are drawn
        separate_labels(ax)
        save_figure(ax, out / f"failures{sfx}.png")
        written.append(out / f"failures{sfx}.png")
    return written, results


def complete_zones(result, model, accuracy=None):
    """The result with zones and C-spaces filled in where a resumed run left them
    out (they are not part of the checkpoint)."""
    import dataclasses

    from cspace.defects import reference

    from ..loop import operating_zones
    kw = {}
    for which, nom, tol in (("initial", result.initial_nominal, result.initial_tol),
                            ("final", result.nominal, result.tol)):
        if getattr(result, f"zones_{which}") is None:
            design = model.with_nominal(nom).with_tolerances(tol)
            ref = reference(design, accuracy, result.d)
            kw[f"zones_{which}"] = operating_zones(design, ref, accuracy)
            kw[f"spaces_{which}"] = ref.spaces
    return dataclasses.replace(result, **kw) if kw else result


def in_declared_units(result, model):
    """``result`` reporting each parameter in the unit its model file states
    it in (:func:`synthesis.cli.convert.declared_units`: degrees for
    ``"unit": "deg"``), its vectors still in the library's units; ``result``
    itself when every parameter is reported in the library's unit."""
    import dataclasses

    from .convert import declared_units
    units = declared_units(model)
    if tuple(model.names) != tuple(result.names) or all(k == 1.0 for _, k in units):
        return result
    return dataclasses.replace(result, param_units=tuple(u for u, _ in units),
                               param_scales=tuple(k for _, k in units))


def file_suffixes(names) -> list:
    """File-name suffixes ``_<name>`` for pairs: characters other than letters,
    digits, ``.``, ``-`` and ``_`` become ``_`` (a name never leaves the output
    folder), and names that collide get their pair index appended."""
    import re
    slugs = [re.sub(r"[^A-Za-z0-9._-]+", "_", str(n)).strip("._") or "pair" for n in names]
    out = []
    for i, sl in enumerate(slugs):
        out.append(f"_{sl}" if slugs.count(sl) == 1 else f"_{sl}_{i}")
    return out


def write_outputs(result, model, out, *, plots: bool = True, verification=None,
                  accuracy=None, command: str | None = None, removed=(),
                  zone_plots: bool = True, failures=None, operating=None,
                  previous: str | None = None) -> list:
    """Write the report, the geometry and the figures of a run into ``out``.
    Returns the paths written (the report last).

    ``command`` is the command line shown in ``report.md``; ``removed`` are
    defective vectors of the run (:attr:`SynthesisState.removed`) to mark in
    ``failures.png``.  ``zone_plots=False`` leaves out the figures that need
    computing (the zones before and after, and ``failures.png``, which
    re-tests vectors): a stopped run writes its report within seconds.
    ``failures``: those re-tests, done already (:func:`failure_retests`).
    ``operating``: the run's :func:`operating_point` (the command line passes
    it; not recorded without it); a follower start the library guessed is
    written into ``model_initial.json``, so that a run from it is the same
    mechanism.
    ``previous``: the subfolder an earlier run's outputs were moved to (named
    in the report)."""
    import dataclasses

    from cspace.io import atomic_write, dumps, model_motion, save_pair
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    result = in_declared_units(result, model)
    written = []
    final = model.with_nominal(result.nominal).with_tolerances(result.tol)
    initial = model.with_nominal(result.initial_nominal).with_tolerances(result.initial_tol)
    if getattr(model, "q2_start", None) is None and operating:
        # the start the run used, stated: a rerun from the file is the same mechanism
        initial = dataclasses.replace(initial, q2_start=tuple(o["q2_start"] for o in operating))
    # with the operating point and the run's d: the files analysed again are
    # the same mechanisms
    motion = model_motion(initial, result.d)
    written.append(save_pair(final.build(), out / "pair.json", motion))
    written.append(save_pair(initial.build(), out / "pair_initial.json", motion))
    from mechanisms.userfile import save_model
    try:
        written.append(save_model(final, out / "model.json"))
        written.append(save_model(initial, out / "model_initial.json"))
    except InputError:
        pass    # a model made in Python by a user: its geometry is code
    marked = None       # the re-tests marked in failures.png, for report.md
    if plots:
        from cspace.plotting import plain_text, plot_zones, save_figure
        if zone_plots:
            result = complete_zones(result, model, accuracy)
        dpi = result.defects_per_iteration()
        n0 = f"{dpi[0]} defective vector(s)" if dpi else "not tested"
        n1 = f"{dpi[-1]} defective vector(s)" if dpi else "not tested"
        suffixes = []
        if zone_plots:
            names = [cs.pair.name for cs in result.spaces_initial]
            suffixes = (file_suffixes(names) if len(result.zones_final) > 1
                        else [""] * len(names))
        zoned = (zip(result.zones_initial, result.zones_final, result.spaces_initial,
                     result.spaces_final, suffixes) if zone_plots else ())
        for zb, za, cb, ca, sfx in zoned:
            save_figure(plot_zones(zb, cb, title=f"{plain_text(cb.pair.name)} before synthesis: "
                                                 f"{len(zb.overlaps)} zone overlap(s) "
                                                 f"(bound), {n0}"),
                        out / f"zones_before{sfx}.png")
            save_figure(plot_zones(za, ca, title=f"{plain_text(ca.pair.name)} after synthesis: "
                                                 f"{len(za.overlaps)} zone overlap(s) "
                                                 f"(bound), {n1}"),
                        out / f"zones_after{sfx}.png")
            save_figure(plot_zones_before_after(zb, za, cb, ca,
                                                defects=(dpi[0], dpi[-1]) if dpi else None),
                        out / f"zones{sfx}.png")
            written += [out / f"zones_before{sfx}.png", out / f"zones_after{sfx}.png",
                        out / f"zones{sfx}.png"]
        if result.history:
            save_figure(plot_defect_history(result), out / "defects.png")
            written.append(out / "defects.png")
        save_figure(plot_changes(result), out / "changes.png")
        save_figure(plot_parts_before_after(result, model), out / "parts.png")
        written += [out / "changes.png", out / "parts.png"]
        if len(removed) and zone_plots:
            drawn, marked = _failure_plots(result, model, out, suffixes, removed, accuracy,
                                           failures)
            written += drawn
    rep = result.to_dict()
    scales = deviation_scales(model)
    Ls = [f"L = {L:.6g} {unit} for {name!r}" for name, unit, L in scales if L is not None]
    own = [f"{nm} in {result.unit_of(i)}" for i, nm in enumerate(result.names)
           if result.unit_of(i) != result.vector_unit_of(i)]
    values = (f"lengths in {result.units}, angles in rad (each parameter's unit: "
              f"parameter_units)" if not own else
              f"changes, changed and shrunk in each parameter's own unit (parameter_units: "
              f"{', '.join(own)}); the vectors initial, final and history (and e_angle) in "
              f"the library's units, lengths in {result.units} and angles in rad "
              f"(vector_units), as checkpoint.json and --params lists hold them")
    rep["units_note"] = (f"{values}; d in the C-space metric "
                         f"(rad, or slide / characteristic length"
                         + (f"; {', '.join(Ls)}" if Ls else "") + ")")
    if operating:
        rep["operating_point"] = [dict(o) for o in operating]
    if verification:
        rep["verification"] = {k: v.to_dict() for k, v in verification.items()}
    verdict = verification_verdict(result, verification)
    if verdict is not None and not verdict["passed"]:
        # the flag: only a final box that failed its check carries it
        rep["verification_failed"] = True
        rep["verification_verdict"] = verdict["text"]
    if previous:
        rep["previous_run"] = previous
    # only files in the folder: checkpoint.json is the command line's (or a
    # caller's) and is listed when it is there
    files = sorted(Path(p).name for p in written) + ["report.json", "report.md"]
    if (out / "checkpoint.json").is_file():
        files.append("checkpoint.json")
    rep["files"] = files
    written.append(atomic_write(out / "report.md",
                                markdown_report(result, verification=verification, files=files,
                                                command=command, scales=scales,
                                                operating=operating, previous=previous,
                                                failures=marked)))
    written.append(atomic_write(out / "report.json", dumps(rep)))
    return [Path(p) for p in written]
