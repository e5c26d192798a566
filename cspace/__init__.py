"""cspace: configuration-space analysis of planar higher-pair mechanisms.

Index
-----
errors      the exception tree (CSpaceError, InputError, DegenerateGeometryError, ...)
accuracy    Accuracy: every approximating knob, with presets fast/default/precise
tolerances  named numeric tolerances (rounding, division guards, probe steps) and why
argcheck    conversion of user input at public boundaries (getvector, getint, getseed, ...)
geom2d      2-D transforms, the one family of circle/line intersections (branches, kinds)
geometry    values: Line, Arc, Loop, Part, Pair and the Rotation/Translation axes
features    the features of a part: vertices, lines, arcs and their free sides
equations   the two closed-form contact equations of a feature pair, and their kernels
pruning     broad phase: the feature pairs of two parts that can ever touch
near        feature pairs the nominal keeps apart but a variant in the box may bring together
roots       adaptive polylines and a vectorised bracketing root finder
contact     contact curves between the features of two fixed-axis parts
cache       reuse of contact curves across variants of one design
freespace   configuration_space: free space by a sweep over the driver axis, its graph
overlap     exact part-overlap and distance tests on the true line/arc geometry
simulate    quasi-static kinematic simulation of the follower in the free space
match       does a variant's free space have the nominal topology?
metric      the C-space metric: a slide of one characteristic length counts as one radian
model       ParametricModel: the contract of a parametric model that defects and zones read
zones       contact zones: the band each contact curve sweeps over the tolerance box
defects     the defect test: is a variant of a parametric model defective?
io          the pair and C-space JSON files, and atomic writes
plotting    plot_* functions and figures (matplotlib imported on first use)
batch       defect margins of many variants in one pass (imported on use)

Only ``errors``, ``accuracy`` and ``geom2d`` are loaded by ``import cspace``;
import the others by name, e.g. ``from cspace.freespace import configuration_space``.
"""

from .accuracy import Accuracy, PRESETS, as_accuracy
from .errors import *  # noqa: F401,F403
from . import geom2d

__version__ = "0.1.0"
