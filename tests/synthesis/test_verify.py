"""Monte Carlo verification of a box: the samples, the seed in every accepted
form, and the checks of the sample count and the seed."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from cspace.errors import InputError
from synthesis.executors import make_executor
from synthesis.verify import MAX_SAMPLES, box_samples, check_samples, check_seed, monte_carlo

NOM = np.array([1.0, -2.0, 0.5])
TOL = np.array([0.1, 0.0, 0.02])


def _documented(nominal, tol, n, seed, corners=0.5):
    """The samples as the module docstring states them: default_rng(seed),
    corners first (a random sign per parameter), then uniform interior."""
    rng = np.random.default_rng(seed)
    nc = int(round(corners * n))
    c = nominal + tol * rng.choice([-1.0, 1.0], size=(nc, len(nominal)))
    u = nominal + tol * rng.uniform(-1.0, 1.0, size=(n - nc, len(nominal)))
    return np.vstack([c, u])


@pytest.mark.parametrize("n, corners", [(1, 0.5), (9, 0.5), (40, 0.25), (10, 0.0), (10, 1.0)])
def test_box_samples_of_an_int_seed_are_the_documented_stream(n, corners):
    s = box_samples(NOM, TOL, n, seed=7, corners=corners)
    assert_array_equal(s, _documented(NOM, TOL, n, 7, corners))
    nc = int(round(corners * n))
    assert_allclose(np.abs(s[:nc] - NOM), np.broadcast_to(TOL, (nc, 3)), atol=1e-12)
    assert np.all(np.abs(s - NOM) <= TOL + 1e-12)
    assert np.all(s[:, 1] == NOM[1])          # zero tolerance stays nominal


def test_box_samples_take_a_generator_or_none():
    a = box_samples(NOM, TOL, 20, seed=np.random.default_rng(7))
    assert_array_equal(a, box_samples(NOM, TOL, 20, seed=7))
    assert_array_equal(box_samples(NOM, TOL, 20, seed=np.int64(7)), a)
    # a Generator is advanced: the next draw from it differs
    g = np.random.default_rng(7)
    assert not np.array_equal(box_samples(NOM, TOL, 20, seed=g), box_samples(NOM, TOL, 20, seed=g))
    assert box_samples(NOM, TOL, 20, seed=None).shape == (20, 3)


@pytest.mark.parametrize("seed", [-1, 1.5, "3", True])
def test_box_samples_refuse_a_bad_seed(seed):
    with pytest.raises(InputError, match=r"seed must be an int >= 0, a numpy\.random\.Generator "
                                         r"or None, got "):
        box_samples(NOM, TOL, 4, seed=seed)


@pytest.mark.parametrize("corners", ["half", True, math.nan, None, -0.1, 1.5])
def test_box_samples_refuse_a_bad_corner_share(corners):
    """corners='half' raised a TypeError from a comparison."""
    with pytest.raises(InputError, match=r"corners must be a fraction in \[0, 1\] \(the share "
                                         r"of samples at box corners\), got "):
        box_samples(NOM, TOL, 4, corners=corners)


@pytest.mark.parametrize("n", [0, MAX_SAMPLES + 1, 2.0, True, "5"])
def test_sample_count_is_checked(n):
    with pytest.raises(InputError, match=rf"^the number of samples must be an int in "
                                         rf"\[1, {MAX_SAMPLES}\], got ") as e:
        check_samples(n)
    assert e.value.name == "n"
    with pytest.raises(InputError, match="the number of samples"):
        box_samples(NOM, TOL, n)


def test_recorded_seed_is_checked_as_an_int():
    assert check_seed(np.int64(3)) == 3
    with pytest.raises(InputError, match=r"^seed must be an int >= 0, got -5$"):
        check_seed(-5)


@pytest.fixture(scope="module")
def recip():
    from mechanisms.models import reciprocating_cam
    return reciprocating_cam()


def test_monte_carlo_records_an_int_seed_and_none_for_a_generator(recip):
    with make_executor("serial") as ex:
        a = monte_carlo(recip, 4, seed=5, accuracy="fast", executor=ex)
        b = monte_carlo(recip, 4, seed=np.random.default_rng(5), accuracy="fast", executor=ex)
    assert a.seed == 5 and b.seed is None
    assert_array_equal(a.samples, box_samples(recip.nominal, recip.tol, 4, seed=5))
    assert_array_equal(a.samples, b.samples)
    assert a.defective == b.defective
    assert a.to_dict()["seed"] == 5 and b.to_dict()["seed"] is None


def test_monte_carlo_keeps_the_messages_of_its_first_defective_samples():
    from cspace.defects import is_defective
    from mechanisms.models import eccentric_cam
    wide = eccentric_cam(0.03)
    with make_executor("serial") as ex:
        r = monte_carlo(wide, 12, seed=3, accuracy="fast", executor=ex)
    assert r.n_defective > 0
    assert len(r.messages) == min(r.n_defective, 5)
    # each the defect test's own message of that sample
    for i, msg in zip(r.defective, r.messages):
        assert msg == is_defective(wide, r.samples[i], accuracy="fast").message
