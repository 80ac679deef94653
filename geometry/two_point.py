"""Two-point contact of a peg in a hole: the closed forms placement needs (the thesis, ch. 3).

d: peg width/diameter, D: hole width/diameter (mm), l_d: insertion depth along the
peg from its tip to the contact point at the hole's mouth (mm). Angles in radians.
"""
import math

from geometry.errors import InputError


def _check_widths(d: float, D: float) -> None:
    if not 0 < d < D:
        raise InputError(f"peg width d = {d}, hole width D = {D}: need 0 < d < D")


def clearance_ratio(d: float, D: float) -> float:
    """c = (D - d) / D."""
    _check_widths(d, D)
    return (D - d) / D


def l_crit(d: float, D: float) -> float:
    """Smallest insertion depth with two-point contact (mm)."""
    _check_widths(d, D)
    return math.sqrt(D * D - d * d)


def l_2p(d: float, l_d: float) -> float:
    """Distance between the two contact points (mm)."""
    return math.hypot(d, l_d)


def tilt_two_point(d: float, D: float, l_d: float) -> float:
    """Peg tilt theta in two-point contact at depth l_d (rad); needs l_d >= l_crit."""
    if l_d < l_crit(d, D):
        raise InputError(f"insertion_depth = {l_d}: below l_crit = {l_crit(d, D):.6g}, no two-point contact")
    l2p = l_2p(d, l_d)
    return math.acos(d / l2p) - math.acos(D / l2p)


def tilt_crit(d: float, D: float) -> float:
    """Tilt at l_d = l_crit, the largest two-point-contact tilt (rad)."""
    _check_widths(d, D)
    return math.acos(d / D)
