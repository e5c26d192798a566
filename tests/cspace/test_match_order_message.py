"""A contact sequence whose curves come in another order names the first
contacts that differ (a user's 3-slot Geneva wheel: as the pin leaves the
slot, the locking disk meets the next lock arc before the pin clears the
slot's corner).  The message used to say only "the same curves bound the
channel in a different order"."""

from pathlib import Path

import numpy as np

from cspace.defects import is_defective, reference
from mechanisms.userfile import load_model

DATA = Path(__file__).resolve().parent / "data"
VARIANT = [0.02, -0.02, 39.98, 0.02, 34.641016151378, 2.5, 31.72, 40.05, 19.55, 40.02, 31.98,
           2.95, 4.0]


def test_a_changed_order_names_the_contacts():
    m = load_model(DATA / "geneva3_user.json")
    ref = reference(m, "fast", 0.025)
    r = is_defective(m, np.array(VARIANT), ref=ref)
    assert r.defective
    assert ("the same curves bound the channel in a different order: contact 5 of the "
            "nominal's sequence is 'driver:pin|wheel:slot0.left^lock1', the variant's "
            "'driver:lock_disk|wheel:lock1^slot1.right' (below the follower)") in r.message
    ch = next(c for m_ in r.matches for c in m_.changes)
    assert set(ch.labels) == {"driver:pin|wheel:slot0.left^lock1",
                              "driver:lock_disk|wheel:lock1^slot1.right"}


def test_a_window_edge_in_a_changed_sequence_is_named():
    """A crank pin in a lever's slot drawn with huge tolerances: a variant
    whose slot crosses itself has cells no contact bounds (the follower free
    to its window edge) in its contact sequence.  The message names that
    edge; it listed an empty curve label ('')."""
    from pathlib import Path
    from cspace.defects import is_defective
    from mechanisms.userfile import load_model
    m = load_model(Path(__file__).parent / "data" / "crank_lever.json")
    u = dict(cx=0.02, cy=-0.02, R=45.0, r=1.0, w=2.05, a=50.0, b=40.05, px=-0.02, py=-50.02)
    msg = is_defective(m, u, accuracy="fast").message
    assert "curves appeared" in msg and "none (window edge)" in msg, msg
    assert "''" not in msg and '""' not in msg
