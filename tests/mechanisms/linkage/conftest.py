import pytest

from mechanisms.linkage import FourBar


@pytest.fixture
def paper_fourbar():
    """[Shin & Choi 1995] Table 1 (crossed branch, ground along +x)."""
    return FourBar.from_lengths(13.55, 8.0, 5.25, 13.3, lp=3.816, alpha=38.0,
                                assembly="crossed", unit="deg")


@pytest.fixture
def crank_rocker():
    return FourBar.from_lengths(4.0, 1.5, 3.5, 3.0, lp=2.0, alpha=0.4)


# crank angle (deg, from the ground line) at which Table 2 of [Shin & Choi 1995] is reproduced:
# the exact column holds for 62.9342..62.9389 deg, the linear column needs the entry at
# delta = 60 deg on its rounding tie 0.29615e-2 (printed +0.2962 / -0.2961); see
# docs/fourbar.md
TABLE2_CRANK_DEG = 62.9350229
TABLE2_DELTA_DEG = list(range(0, 361, 30))
TABLE2_EXACT = [0.8105, 0.6387, 0.2916, -0.1342, -0.5216, -0.7672, -0.8088, -0.6382, -0.3006,
                0.1169, 0.5055, 0.7606, 0.8105]
TABLE2_LINEAR = [0.8097, 0.6385, 0.2962, -0.1255, -0.5135, -0.7640, -0.8097, -0.6385, -0.2961,
                 0.1255, 0.5135, 0.7640, 0.8097]
HALF_UNIT = 0.5e-4 * 1e-2     # half a unit of the 4th printed digit (x 1e-2 rad)
