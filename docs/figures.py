"""Regenerate the figures of docs/models.md:  python docs/figures.py

Labelled drawings of the built-in models (segment names, axes) and their nominal
C-spaces.  Writes into docs/img/.
"""

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

from cspace.plotting import plot_cspace, plot_parts, save_figure  # noqa: E402
from mechanisms.analysis import model_cspaces  # noqa: E402
from mechanisms.models import BUILTIN  # noqa: E402

IMG = Path(__file__).resolve().parent / "img"

POSES = {"geneva": [(0.0, 0.0), (math.pi, -math.pi / 4)],
         "reciprocating_cam": [(0.0, 0.45), (math.pi / 6, 0.0)],
         "optical_filter": [(-math.pi / 2, 0.0), (math.pi, -math.pi / 4)],
         "eccentric_cam": [(0.0, 0.0), (math.pi / 2, 0.5)]}


def main():
    IMG.mkdir(exist_ok=True)
    for name, factory in BUILTIN.items():
        model = factory()
        spaces = model_cspaces(model)
        pairs = model.pairs()
        for k, (pair, cs) in enumerate(zip(pairs, spaces)):
            sfx = f"_{pair.name}" if len(pairs) > 1 else ""
            for j, q in enumerate(POSES[name]):
                if len(pairs) > 1 and k > 0 and j > 0:
                    continue
                ax = plot_parts(pair, q, label_segments=True,
                                title=f"{pair.name} at q = ({q[0]:.3f}, {q[1]:.3f}) "
                                      f"[{pair.units}]")
                save_figure(ax, IMG / f"model_{name}{sfx}_pose{j}.png")
            save_figure(plot_cspace(cs), IMG / f"model_{name}{sfx}_cspace.png")
            print("wrote", name, pair.name)


if __name__ == "__main__":
    main()
