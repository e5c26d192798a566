"""Spatial linkage kinematics by Hartenberg-Denavit matrices ([Kim 1985]).

Index
-----
loops       Joint, JointType (R, P, C = R + P, S = 3 R), HDFrame, Loop, make_loop,
            hd_matrix (standard or the paper's layout), Q_THETA / Q_S operators
solve       solve_pose, solve_path (damped Newton-Raphson with continuation),
            velocity, acceleration (same M matrix), loop_product, loop_residual,
            frame_transforms, point_motion; SolverOptions, LoopStatus, LoopPose,
            LoopPath, PointMotion
builders    planar_fourbar, spherical_4r, rccc, rssr -> Linkage; hd_from_frames
closedform  input-output equations for cross-checks: freudenstein,
            spherical_4r_psi, rssr_phi, rccc (spherical indicatrix + linear slides)
plotting    plot_displacement, plot_velocity, plot_acceleration (Figs. 3-5),
            plot_linkage (3-D skeleton); matplotlib imported on call

Units: lengths in model units, angles in radians; builders, :func:`solve_pose` and
:func:`solve_path` accept degrees through ``unit="deg"``.
"""

from .loops import JointType, Joint, HDFrame, Loop, make_loop, hd_matrix, Q_THETA, Q_S
from .solve import (SolverOptions, LoopStatus, LoopPose, LoopPath, PointMotion, loop_product,
                    loop_residual, solve_pose, solve_path, velocity, acceleration,
                    frame_transforms, point_motion, SELECTED_ENTRIES)
from .builders import Linkage, hd_from_frames, planar_fourbar, spherical_4r, rccc, rssr
from . import closedform

__all__ = [
    "JointType", "Joint", "HDFrame", "Loop", "make_loop", "hd_matrix", "Q_THETA", "Q_S",
    "SolverOptions", "LoopStatus", "LoopPose", "LoopPath", "PointMotion", "loop_product",
    "loop_residual", "solve_pose", "solve_path", "velocity", "acceleration",
    "frame_transforms", "point_motion", "SELECTED_ENTRIES",
    "Linkage", "hd_from_frames", "planar_fourbar", "spherical_4r", "rccc", "rssr", "closedform",
]
