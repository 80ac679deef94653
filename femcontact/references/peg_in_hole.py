"""Closed-form peg-in-hole relations (the thesis, ch. 3; Whitney, Mechanical Assemblies ch. 10; Simunovic).

The two-point geometry lives in `geometry.two_point` (placement needs it and geometry
imports nothing from femcontact); the friction-dependent wedging bounds live here.
d: peg width/diameter, D: hole width/diameter (mm), l_d: insertion depth (mm), mu: friction.
"""
from geometry.two_point import clearance_ratio, l_2p, l_crit, tilt_crit, tilt_two_point

__all__ = ["clearance_ratio", "l_2p", "l_crit", "tilt_crit", "tilt_two_point", "l_max", "can_wedge"]


def l_max(d: float, mu: float) -> float:
    """Largest insertion depth at which wedging can occur (mm)."""
    return d * mu


def can_wedge(d: float, D: float, mu: float, l_d: float) -> bool:
    """Geometric wedging condition l_crit <= l_d <= mu * d."""
    return l_crit(d, D) <= l_d <= l_max(d, mu)
