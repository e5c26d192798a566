"""Parametric models.

Index
-----
Model, Parameter     parametric model values (base)
Distribution         how a parameter's made values spread (statistical yield)
geneva               four-slot Geneva pair, 26 parameters, +/-0.018 cm
optical_filter       three cam/follower pairs on one shaft, 17 parameters, +/-0.002 cm
reciprocating_cam    three-finger cam with a sliding yoke, 11 parameters, +/-0.02 cm
BUILTIN              name -> factory
"""
from .base import Distribution, Model, Parameter
from .geneva import geneva
from .optical import optical_filter
from .recip import reciprocating_cam

BUILTIN = {"geneva": geneva, "optical_filter": optical_filter,
           "reciprocating_cam": reciprocating_cam}
