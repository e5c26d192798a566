"""cspace: configuration-space analysis of planar higher-pair mechanisms.

Index
-----
errors      the exception tree (CSpaceError, ...)
accuracy    Accuracy: every approximating knob, with presets fast/default/precise
argcheck    conversion of user input at public boundaries
geom2d      2-D transforms, circle/line intersection with branch handling
batch       defect margins of many variants in one pass (imported on use)
"""

from .accuracy import Accuracy, PRESETS, as_accuracy
from .errors import *  # noqa: F401,F403
from . import geom2d

__version__ = "0.1.0"
