"""mechanisms.linkage: planar four-bar kinematics, mechanical error and clearance dynamics.

Index
-----
fourbar     FourBar value, Assembly branch, Grashof type, solve() over arrays of
            input angles (positions, velocities, accelerations, toggle status)
error       mechanical error from link tolerances and joint clearances: exact
            re-solution, sensitivity linkage (first order), harmonic structure,
            coupler-point error ellipse, Dubowsky condition, worst case, RSS,
            seeded Monte Carlo
clearance   four-bar with a clearance at the coupler-rocker joint: continuous-
            contact joint force and contact loss ([Choi & Bae 1999]), and a
            free-flight-and-impact model with Lankarani-Nikravesh contact
plotting    plot_* functions (matplotlib imported on first use)
"""

from .fourbar import (Assembly, GrashofType, PoseStatus, LinkageTolerances, FourBar,
                      FourBarMotion, InputRange, grashof, solve, input_range)
from .error import (ErrorStatus, EllipseKind, Sensitivity, ErrorCurve, ClosedForm, Harmonic,
                    ErrorEllipse, ToleranceSpec, WorstCase, RSSResult, MonteCarloResult,
                    sensitivity, clearance_gradient, exact_error, linear_error,
                    clearance_b_closed_form, paper_closed_form, harmonic_fit, harmonic_max,
                    coupler_ellipse, dubowsky_deltas, worst_case, rss, monte_carlo)
from .clearance import (ClearanceLinkage, GroundInference, LossKind, ContactLoss, ContactForce,
                        FlightEvent, FreeFlightResult, FlightStatus, infer_ground,
                        rocker_zero_acceleration, continuous_contact, free_flight,
                        hertz_stiffness, rpm_to_rad_s)

__all__ = [
    "Assembly", "GrashofType", "PoseStatus", "LinkageTolerances", "FourBar", "FourBarMotion",
    "InputRange", "grashof", "solve", "input_range",
    "ErrorStatus", "EllipseKind", "Sensitivity", "ErrorCurve", "ClosedForm", "Harmonic",
    "ErrorEllipse", "ToleranceSpec", "WorstCase", "RSSResult", "MonteCarloResult",
    "sensitivity", "clearance_gradient", "exact_error", "linear_error",
    "clearance_b_closed_form", "paper_closed_form", "harmonic_fit", "harmonic_max",
    "coupler_ellipse", "dubowsky_deltas", "worst_case", "rss", "monte_carlo",
    "ClearanceLinkage", "GroundInference", "LossKind", "ContactLoss", "ContactForce",
    "FlightEvent", "FreeFlightResult", "FlightStatus", "infer_ground",
    "rocker_zero_acceleration", "continuous_contact", "free_flight", "hertz_stiffness",
    "rpm_to_rad_s",
]
