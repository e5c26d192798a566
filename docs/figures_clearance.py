"""Regenerate the clearance-joint figures of docs/fourbar.md ("Free flight"):

    python docs/figures_clearance.py

``clearance_loss_positions.png``: the contact-loss crank angles of the
continuous-contact model against crank speed, with the strongest impacts of
one default free-flight run per speed (its analysed revolutions);
``clearance_free_flight.png``: the contact force of one default free-flight
run at 100 rpm against the continuous-contact force.  100 um clearance.
Writes into docs/img/.
"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from mechanisms.linkage import ClearanceLinkage, continuous_contact, free_flight  # noqa: E402
from mechanisms.linkage.plotting import plot_loss_positions  # noqa: E402

IMG = Path(__file__).resolve().parent / "img"
SPEEDS = (50, 100, 200, 300)
CLEARANCE = 100e-6


def main():
    IMG.mkdir(exist_ok=True)
    link = ClearanceLinkage.reference()
    cont = [continuous_contact(link, rpm, CLEARANCE) for rpm in SPEEDS]
    flights = [free_flight(link, rpm, CLEARANCE) for rpm in SPEEDS]
    ax = plot_loss_positions(cont, flights=flights)
    ax.set_title("Contact loss vs speed, 100 um (one free-flight run per speed)")
    ax.figure.tight_layout()
    ax.figure.savefig(IMG / "clearance_loss_positions.png", dpi=110)
    plt.close(ax.figure)

    f = flights[SPEEDS.index(100)]
    c = cont[SPEEDS.index(100)]
    fig, ax = plt.subplots(figsize=(7.5, 3.8))
    ax.plot(np.degrees(f.crank_angle) % 360.0, f.force, ".", ms=2,
            label="free flight + impact (last revolution)")
    ax.plot(np.degrees(c.crank_angle), c.R, lw=1.0, label="continuous contact")
    ax.set_yscale("symlog", linthresh=10.0)
    ax.set_xlim(0, 360)
    ax.set_xlabel("crank angle (deg)")
    ax.set_ylabel("contact force (N)")
    ax.set_title("100 rpm, 100 um")
    ax.legend(fontsize="small")
    fig.tight_layout()
    fig.savefig(IMG / "clearance_free_flight.png", dpi=110)
    plt.close(fig)
    for rpm, fl in zip(SPEEDS, flights):
        print(rpm, "rpm:", fl)


if __name__ == "__main__":
    main()
