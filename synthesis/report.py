"""Figures and files of a synthesis run: contact zones before and after (seed 003
Figs. 3, 7, 9), the defect count per iteration, and the output folder.

Output folder (``write_outputs``)
--------------------------------
``report.json``
    :meth:`SynthesisResult.to_dict` plus the model units, the Monte Carlo
    verification (when run) and the list of files written.
``pair.json`` / ``pair_initial.json``
    The final and the initial nominal geometry (``cspace-pair`` or
    ``cspace-assembly``).
``model.json``
    The synthesized model as a ``cspace-model`` file (only for models read from
    a model file: their geometry is data).
``zones_before{_pair}.png``, ``zones_after{_pair}.png``, ``zones{_pair}.png``
    The zones of the operating channel of the initial and final designs, and
    both side by side.
``defects.png``
    Defective check-list vectors per iteration.
"""

from __future__ import annotations

from pathlib import Path


__all__ = ["plot_zones_before_after", "plot_defect_history", "write_outputs",
           "complete_zones"]


def plot_zones_before_after(zones_before, zones_after, cs_before, cs_after, *, unit="rad",
                            title=None):
    """Two panels: zones of the initial and of the final design.  Returns the
    right-hand Axes (``ax.figure`` is the figure)."""
    from cspace.plotting import _plt, plot_zones
    plt = _plt()
    fig, (a0, a1) = plt.subplots(1, 2, figsize=(16, 6.5), sharex=True, sharey=True)
    plot_zones(zones_before, cs_before, ax=a0, unit=unit,
               title=f"before: {len(zones_before.overlaps)} zone overlap(s)")
    plot_zones(zones_after, cs_after, ax=a1, unit=unit,
               title=f"after: {len(zones_after.overlaps)} zone overlap(s)")
    fig.suptitle(title or f"Contact zones of {cs_before.pair.name}")
    return a1


def plot_defect_history(result, *, ax=None):
    """Defective check-list vectors and check-list size per iteration."""
    from cspace.plotting import new_axes
    ax = new_axes(ax, (7, 4))
    it = [h.iteration for h in result.history]
    ax.plot(it, result.defects_per_iteration(), "o-", color="tab:red", label="defective vectors")
    ax.plot(it, [h.counts.get("checklist", 0) for h in result.history], "s--",
            color="tab:gray", lw=0.8, label="check-list size")
    ax.set_xlabel("iteration")
    ax.set_ylabel("vectors")
    ax.set_xticks(it)
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=8)
    ax.set_title(f"{result.model}: {result.status.name.lower()} after {result.nit} iteration(s), "
                 f"e = {result.e:.4g} {result.units}")
    return ax


def complete_zones(result, model, accuracy=None):
    """The result with zones and C-spaces filled in where a resumed run left them
    out (they are not part of the checkpoint)."""
    import dataclasses

    from cspace.defects import reference

    from .loop import operating_zones
    kw = {}
    for which, nom, tol in (("initial", result.initial_nominal, result.initial_tol),
                            ("final", result.nominal, result.tol)):
        if getattr(result, f"zones_{which}") is None:
            design = model.with_nominal(nom).with_tolerances(tol)
            ref = reference(design, accuracy, result.d)
            kw[f"zones_{which}"] = operating_zones(design, ref, accuracy)
            kw[f"spaces_{which}"] = ref.spaces
    return dataclasses.replace(result, **kw) if kw else result


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
                  accuracy=None) -> list:
    """Write the report, the geometry and the figures of a run into ``out``.
    Returns the paths written (the report last)."""
    from cspace.io import atomic_write, dumps, save_pair
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    final = model.with_nominal(result.nominal).with_tolerances(result.tol)
    written.append(save_pair(final.build(), out / "pair.json"))
    written.append(save_pair(model.with_nominal(result.initial_nominal).build(),
                             out / "pair_initial.json"))
    try:
        from mechanisms.userfile import ModelFileBuilder, save_model
        if isinstance(final.builder, ModelFileBuilder):
            written.append(save_model(final, out / "model.json"))
    except ImportError:  # pragma: no cover - part of the package
        pass
    if plots:
        from cspace.plotting import plain_text, plot_zones, save_figure
        result = complete_zones(result, model, accuracy)
        multi = len(result.zones_final) > 1
        names = [cs.pair.name for cs in result.spaces_initial]
        suffixes = file_suffixes(names) if multi else [""] * len(names)
        for zb, za, cb, ca, sfx in zip(result.zones_initial, result.zones_final,
                                       result.spaces_initial, result.spaces_final, suffixes):
            save_figure(plot_zones(zb, cb, title=f"{plain_text(cb.pair.name)} before synthesis: "
                                                 f"{len(zb.overlaps)} zone overlap(s)"),
                        out / f"zones_before{sfx}.png")
            save_figure(plot_zones(za, ca, title=f"{plain_text(ca.pair.name)} after synthesis: "
                                                 f"{len(za.overlaps)} zone overlap(s)"),
                        out / f"zones_after{sfx}.png")
            save_figure(plot_zones_before_after(zb, za, cb, ca), out / f"zones{sfx}.png")
            written += [out / f"zones_before{sfx}.png", out / f"zones_after{sfx}.png",
                        out / f"zones{sfx}.png"]
        if result.history:
            save_figure(plot_defect_history(result), out / "defects.png")
            written.append(out / "defects.png")
    rep = result.to_dict()
    rep["units_note"] = (f"lengths in {result.units}, angles in rad; d in the C-space metric "
                         f"(rad, or slide / characteristic length)")
    if verification:
        rep["verification"] = {k: v.to_dict() for k, v in verification.items()}
    rep["files"] = sorted(Path(p).name for p in written) + ["report.json", "checkpoint.json"]
    written.append(atomic_write(out / "report.json", dumps(rep)))
    return [Path(p) for p in written]
