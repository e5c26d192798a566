"""Regenerate the manipulator and spatial-linkage figures in docs/img.

Run from the repository root:  python docs/figures_manip_spatial.py
"""

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from mechanisms.manipulators import design  # noqa: E402
from mechanisms.manipulators.plotting import plot_ldi_map, plot_workspace  # noqa: E402
from mechanisms.spatial import rccc, solve_path  # noqa: E402
from mechanisms.spatial.plotting import (plot_acceleration, plot_displacement,  # noqa: E402
                                         plot_linkage, plot_velocity)

OUT = Path(__file__).resolve().parent / "img"
OUT.mkdir(exist_ok=True)

pap = design("2-PaP", 1.0, 60, unit="deg").model
ppa = design("2-PPa", 1.0, 30, unit="deg").model

# Fig. 5: LDI mesh plots over the prescribed square (w = 1).
fig = plt.figure(figsize=(10, 4.2))
ax = fig.add_subplot(1, 2, 1, projection="3d")
plot_ldi_map(pap, ax=ax, n=31)
ax.set_title("(a) 2-PaP, theta_L = 60 deg (LDI in units of w)")
ax = fig.add_subplot(1, 2, 2, projection="3d")
plot_ldi_map(ppa, ax=ax, n=31, color="C1")
ax.set_title("(b) 2-PPa, theta_L = 30 deg")
fig.tight_layout()
fig.savefig(OUT / "manip_ldi_maps.png", dpi=110)
plt.close(fig)

# Figs. 3-4: workspaces.
fig, axs = plt.subplots(1, 2, figsize=(11, 5))
plot_workspace(pap, ax=axs[0])
axs[0].set_title("2-PaP, theta_L = 60 deg, w = 1")
plot_workspace(ppa, ax=axs[1])
axs[1].set_title("2-PPa, theta_L = 30 deg, w = 1")
fig.tight_layout()
fig.savefig(OUT / "manip_workspaces.png", dpi=110)
plt.close(fig)

# [Kim 1985] Figs. 3-5: an RCCC over one input revolution.
lk = rccc((30, 80, 60, 70), (1.0, 3.0, 2.5, 3.5), 0.5, 0, unit="deg")
path = solve_path(lk.loop, np.linspace(0, 2 * math.pi, 361), lk.q0)
labels = ["theta0 (input)", "theta1 (C1)", "s1 (C1)", "theta2 (C2)", "s2 (C2)",
          "theta3 (C3, output)", "s3 (C3)"]
for fn, name in ((plot_displacement, "displacement"), (plot_velocity, "velocity"),
                 (plot_acceleration, "acceleration")):
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(7, 6.5), sharex=True)
    fn(path, ax=ax, loop=lk.loop, labels=labels, variables=[1, 3, 5])
    fn(path, ax=ax2, loop=lk.loop, labels=labels, variables=[2, 4, 6])
    ax.set_title(f"RCCC {name} (alpha = 30/80/60/70 deg, a = 1/3/2.5/3.5, s0 = 0.5)")
    ax2.set_ylabel(ax2.get_ylabel().replace("(deg, or length)", "(length)"))
    ax.set_xlabel("")
    fig.tight_layout()
    fig.savefig(OUT / f"spatial_rccc_{name}.png", dpi=110)
    plt.close(fig)

fig = plt.figure(figsize=(6, 5))
ax = fig.add_subplot(projection="3d")
for k in range(0, 360, 45):
    plot_linkage(lk, path.q[k], ax=ax, color=plt.cm.viridis(k / 360), lw=1.0)
ax.set_title("RCCC frame origins every 45 deg of input (red: joint axes)")
fig.tight_layout()
fig.savefig(OUT / "spatial_rccc_skeleton.png", dpi=110)
plt.close(fig)
print("written to", OUT)
