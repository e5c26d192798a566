"""``ConfigurationSpace.classify`` returns ``Status`` members (issue 24)."""

import numpy as np

from cspace.freespace import Status, configuration_space


def test_classify_returns_status_members():
    from mechanisms.models import reciprocating_cam

    cs = configuration_space(reciprocating_cam().build(), accuracy="fast")
    st = cs.classify([[0.0, 0.0], [0.0, cs.window[3]], [0.5, 0.0]])
    assert all(isinstance(s, Status) for s in st)
    assert st[0] is Status.FREE or st[0] is Status.BLOCKED or st[0] is Status.CONTACT
    assert [s.name for s in st] == [Status(int(s)).name for s in st]
    # still comparable with the int values and usable as a mask
    assert np.array_equal(st == Status.FREE, np.array([int(s) for s in st]) == 0)
    assert repr(st[0]).startswith("<Status.")
