"""Parametric models.

Index
-----
base         Model, Parameter (parametric model values) and Distribution (how a
             parameter's made values spread, for the statistical yield)
geneva       geneva(): four-slot Geneva pair, 26 parameters, +/-0.018 cm
optical      optical_filter(): three cam/follower pairs on one shaft, 17 parameters,
             +/-0.002 cm
recip        reciprocating_cam(): three-finger cam with a sliding yoke, 11 parameters,
             +/-0.02 cm
eccentric    eccentric_cam(): eccentric disc under a spring-loaded flat follower,
             7 parameters, +/-0.01 cm

``BUILTIN`` maps each built-in name to its factory.
"""
from .base import Distribution, Model, Parameter
from .eccentric import eccentric_cam
from .geneva import geneva
from .optical import optical_filter
from .recip import reciprocating_cam

BUILTIN = {"geneva": geneva, "optical_filter": optical_filter,
           "reciprocating_cam": reciprocating_cam, "eccentric_cam": eccentric_cam}
