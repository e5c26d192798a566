"""Planar translational parallel manipulators 2-PaP and 2-PPa ([Kim 2007]).

Index
-----
models      TwoPaP, TwoPPa values; builders two_pap, two_ppa (perpendicular actuators,
            the paper's design) and two_ppa_parallel (parallel actuators, Eq. 29)
kinematics  inverse_kinematics, forward_kinematics (branches stated), PoseStatus,
            closed_form_forward (Eq. 15 of [Kim 2007], for cross-checks)
jacobian    jacobians (J_x, J_q, J, velocity map, condition number), Singularity (incl.
            NEAR_SINGULAR), local_design_index (reachable poses only),
            actuator_forces / platform_force (statics)
indices     ldi_map (Fig. 5), global_design_index (GDI = LDI_min / LDI_max, as in the
            tables), closed_form_design_indices (Table 1)
workspace   total_workspace (shapely polygon), leg_region, effective_square, square_fits
design      design (dimensions from w and theta_L), comparison_table (Table 2),
            arrangement_comparison (Table 3), decoupling
plotting    plot_ldi_map, plot_workspace (matplotlib imported on call)

Units: lengths in the model's length unit, angles in radians; builders and
:func:`design` accept degrees through ``unit="deg"``.
"""

from .models import Arrangement, TwoPaP, TwoPPa, two_pap, two_ppa, two_ppa_parallel
from .kinematics import (PoseStatus, IKResult, FKResult, inverse_kinematics, forward_kinematics,
                         closed_form_forward, eq15_forward)
from .jacobian import (Singularity, Jacobians, jacobians, local_design_index, ldi_of_jacobian,
                       StaticsResult, actuator_forces, platform_force)
from .indices import (LDIMap, ldi_map, GDIResult, global_design_index, closed_form_design_indices,
                      table1_closed_form)
from .workspace import leg_region, total_workspace, EffectiveSquare, effective_square, square_fits
from .design import (Design, design, Decoupling, decoupling, ComparisonTable, comparison_table,
                     ArrangementPoint, arrangement_comparison)

__all__ = [
    "Arrangement", "TwoPaP", "TwoPPa", "two_pap", "two_ppa", "two_ppa_parallel",
    "PoseStatus", "IKResult", "FKResult", "inverse_kinematics", "forward_kinematics",
    "closed_form_forward", "eq15_forward",
    "Singularity", "Jacobians", "jacobians", "local_design_index", "ldi_of_jacobian",
    "StaticsResult", "actuator_forces", "platform_force",
    "LDIMap", "ldi_map", "GDIResult", "global_design_index",
    "closed_form_design_indices", "table1_closed_form",
    "leg_region", "total_workspace", "EffectiveSquare", "effective_square", "square_fits",
    "Design", "design", "Decoupling", "decoupling", "ComparisonTable", "comparison_table",
    "ArrangementPoint", "arrangement_comparison",
]
