"""Closed-form input-output equations used to cross-check the HD solver.

Every one of them reduces to ``A cos(x) + B sin(x) = C`` for the output angle x,
solved by :func:`solve_harmonic` on a stated root (``branch = +1`` takes
``atan2(B, A) + acos(C / R)``, ``-1`` the minus sign).  None of them uses HD matrices.

freudenstein
    Planar four-bar, Freudenstein's equation
    ``K1 cos(phi) - K2 cos(theta) + K3 = cos(theta - phi)``, ``K1 = d/a``, ``K2 = d/c``,
    ``K3 = (a^2 - b^2 + c^2 + d^2) / (2 a c)``; phi is the angle of DC from AD.
spherical_4r_psi
    Spherical 4R: the coupler's output-side axis ``z2`` lies on the cone of half-angle
    alpha_2 about the output axis ``z3`` and makes the angle alpha_1 with the input-side
    axis ``z1(theta)``: ``z1 . z2(psi) = cos(alpha_1)``.
rssr_phi
    RSSR: the pins B(theta) and C(phi) stay one coupler length apart,
    ``|B(theta) - C(phi)|^2 = l^2``.
rccc
    RCCC: the rotations are those of the spherical 4R with the same twists (the
    spherical indicatrix); the three slides then follow from the linear translation
    closure ``s1 z1 + s2 z2 + s3 z3 = -(s0 z0 + sum_i a_i x_{i+1})``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["solve_harmonic", "freudenstein", "spherical_4r_psi", "spherical_4r_z2",
           "RSSRGeometry", "rssr_phi", "RCCCClosedForm", "rccc"]

#: Relative slack on |C| <= R before a harmonic equation counts as unsolvable;
#: covers rounding at exact limit positions.
_HARMONIC_TOL = 1e-12


def solve_harmonic(A, B, C, branch):
    """Solve ``A cos x + B sin x = C``; returns ``(x, ok)`` (x finite, ok False if no root)."""
    R = math.hypot(A, B)
    if R == 0.0:
        return 0.0, False
    ratio = C / R
    ok = abs(ratio) <= 1.0 + _HARMONIC_TOL
    return math.atan2(B, A) + branch * math.acos(min(1.0, max(-1.0, ratio))), ok


def freudenstein(crank, coupler, rocker, ground, theta, branch):
    """Rocker angle phi (rad, of DC from AD) of a planar four-bar; ``(phi, ok)``."""
    a, b, c, d = crank, coupler, rocker, ground
    k1, k2 = d / a, d / c
    k3 = (a * a - b * b + c * c + d * d) / (2 * a * c)
    return solve_harmonic(k1 - math.cos(theta), -math.sin(theta),
                          k2 * math.cos(theta) - k3, branch)


def _sph_basis(a3):
    z3 = np.array([0.0, math.sin(a3), math.cos(a3)])
    u = np.array([1.0, 0.0, 0.0])
    return z3, u, np.cross(z3, u)


def spherical_4r_z2(alphas, psi):
    """Output-side coupler axis for output angle psi (about z3, from the ground's x axis)."""
    a2, a3 = alphas[2], alphas[3]
    z3, u, v = _sph_basis(a3)
    return math.cos(a2) * z3 + math.sin(a2) * (math.cos(psi) * u + math.sin(psi) * v)


def spherical_4r_psi(alphas, theta, branch):
    """Output angle psi of a spherical 4R at input theta; ``(psi, ok)``.

    Layout: input axis z0 = (0, 0, 1); ground twist alpha_3 puts the output axis at
    ``z3 = (0, sin a3, cos a3)``; the input link turns ``z1`` on the cone of half-angle
    alpha_0 about z0: ``z1 = (sin th sin a0, -cos th sin a0, cos a0)``.
    """
    a0, a1, a2, a3 = alphas
    z1 = np.array([math.sin(theta) * math.sin(a0), -math.cos(theta) * math.sin(a0), math.cos(a0)])
    z3, u, v = _sph_basis(a3)
    return solve_harmonic(math.sin(a2) * (z1 @ u), math.sin(a2) * (z1 @ v),
                          math.cos(a1) - math.cos(a2) * (z1 @ z3), branch)


@dataclass(frozen=True)
class RSSRGeometry:
    """RSSR layout (see :func:`mechanisms.spatial.builders.rssr`)."""

    crank: float
    crank_height: float
    coupler: float
    rocker: float
    offset: float
    twist: float
    rocker_height: float

    @property
    def axis(self) -> np.ndarray:
        return np.array([0.0, math.sin(self.twist), math.cos(self.twist)])

    @property
    def rocker_centre(self) -> np.ndarray:
        return np.array([-self.offset, 0.0, 0.0]) - self.rocker_height * self.axis

    @property
    def basis(self):
        """(e1, e2): orthonormal vectors of the rocker plane; phi is measured from e1."""
        e1 = np.array([1.0, 0.0, 0.0])
        return e1, np.cross(self.axis, e1)

    def crank_pin(self, theta) -> np.ndarray:
        return np.array([self.crank * math.cos(theta), self.crank * math.sin(theta),
                         self.crank_height])

    def rocker_pin(self, phi) -> np.ndarray:
        e1, e2 = self.basis
        return self.rocker_centre + self.rocker * (math.cos(phi) * e1 + math.sin(phi) * e2)

    def phi_of(self, c) -> float:
        """Rocker angle of a pin position c (3,)."""
        e1, e2 = self.basis
        d = np.asarray(c) - self.rocker_centre
        return math.atan2(d @ e2, d @ e1)


def rssr_phi(geo: RSSRGeometry, theta, branch):
    """Rocker angle phi of an RSSR at input theta; ``(phi, ok)``."""
    d = geo.crank_pin(theta) - geo.rocker_centre
    e1, e2 = geo.basis
    r2, l = geo.rocker, geo.coupler
    return solve_harmonic(d @ e1, d @ e2, (d @ d + r2 * r2 - l * l) / (2 * r2), branch)


@dataclass(frozen=True)
class RCCCClosedForm:
    """RCCC pose in closed form: frame origins, axes and the three slides."""

    origins: np.ndarray
    z: np.ndarray
    x: np.ndarray
    slides: np.ndarray
    psi: float
    ok: bool


def rccc(alphas, lengths, s0, theta, branch) -> RCCCClosedForm:
    """RCCC pose at input theta from the spherical indicatrix plus a 3x3 linear solve."""
    a = lengths
    psi, ok = spherical_4r_psi(alphas, theta, branch)
    z0 = np.array([0.0, 0.0, 1.0])
    z1 = np.array([math.sin(theta) * math.sin(alphas[0]), -math.cos(theta) * math.sin(alphas[0]),
                   math.cos(alphas[0])])
    z2 = spherical_4r_z2(alphas, psi)
    z3 = _sph_basis(alphas[3])[0]
    z = np.array([z0, z1, z2, z3])
    x = [np.array([1.0, 0.0, 0.0])]
    for i in range(1, 4):
        x.append(np.cross(z[i - 1], z[i]) / math.sin(alphas[i - 1]))
    x = np.array(x)
    Z = np.stack([z1, z2, z3], -1)
    rhs = -(s0 * z0 + a[0] * x[1] + a[1] * x[2] + a[2] * x[3] + a[3] * x[0])
    det = float(np.linalg.det(Z))
    if abs(det) < 1e-9:
        ok = False
        s = np.zeros(3)
    else:
        s = np.linalg.solve(Z, rhs)
    o = np.zeros((4, 3))
    o[1] = s0 * z0 + a[0] * x[1]
    o[2] = o[1] + s[0] * z1 + a[1] * x[2]
    o[3] = o[2] + s[1] * z2 + a[2] * x[3]
    return RCCCClosedForm(origins=o, z=z, x=x, slides=s, psi=psi, ok=bool(ok))
