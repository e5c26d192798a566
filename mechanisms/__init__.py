"""mechanisms: parametric models and the linkage analyses built on cspace.

Index
-----
models        parametric models: Model, Parameter and the built-in pairs (BUILTIN)
analysis      the C-space and nominal motion of every pair of a model
userfile      parametric model files (``cspace-model`` JSON): read, write, build
expressions   the expression language of model files (whitelisted, never executed)
dimensions    every dimension of a fixed pair a parameter (``import-dxf --tol``)
dxf           DXF drawings in and out (extra ``dxf``)
linkage       four-bar kinematics, mechanical error and clearance dynamics
manipulators  planar translational parallel manipulators 2-PaP and 2-PPa
spatial       spatial linkage kinematics by Hartenberg-Denavit matrices
"""
