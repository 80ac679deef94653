"""Chamfer crossing of a rigid peg whose tip rim is rounded (radius rho), on Whitney's compliant
support (femcontact.references.whitney: same frame, support, depth s and sign conventions).

The rounding of the peg's side `side` is a circle of radius rho centred at
P = tip + side (r - rho) n + rho a (a the peg axis, n its side normal). It touches the hole where
P lies rho from the hole's profile on that side, seen in the mirrored coordinate x' = side x with
E = (D/2, 0) the chamfer's lower edge: the chamfer line above E (unit normal into the hole
(-cos a, sin a)), the wall x' = D/2 below it, and E itself in between (a convex edge: P in the
wedge between the two normals is nearest to E). So the gap is

    g = (P - E).(-cos a, sin a) - rho   chamfer ('chamfer': (P - E).(sin a, cos a) > 0)
    g = |P - E| - rho                   edge ('edge': the rounding rolls over E)
    g = D/2 - x'_P - rho                wall ('one_point': P below E)

with the contact normal on the peg nu = the unit normal of that piece (for the edge (P - E)/|P - E|),
the contact point on the peg P - rho nu, and friction mu N up the profile (the peg slides down):
t' = (nu'_z, -nu'_x). One sliding contact: the unknowns u (support deflection), theta and N solve
the lateral balance, the moment balance about the compliance centre C and g = 0, as in
whitney._residual; Fz = N (nu + mu t)_z, Fx = -K_x u, M (about the tip) as in whitney._state.
For rho -> 0 this is Whitney's sharp corner on the chamfer and the wall; on the chamfer it is the
sharp corner at P on the chamfer line moved rho into the hole, except that the friction acts at
the real contact point (P - rho nu), not at P.
"""
import math

import numpy as np
from scipy.optimize import root

from femcontact.errors import InputError
from femcontact.references.whitney import CANDIDATES, Insertion, axes, contact, cross, dot, pose

PIECES = ("chamfer", "edge", "one_point")


def rounding_centre(p: Insertion, rho: float, side: int, tip, theta: float) -> tuple:
    """Centre P (mm) of the rounding on side `side` (+1 right, -1 left) for the tip centre and tilt."""
    a, n = axes(theta)
    return (tip[0] + side * (p.r - rho) * n[0] + rho * a[0], tip[1] + side * (p.r - rho) * n[1] + rho * a[1])


def profile(p: Insertion, rho: float, side: int, centre) -> tuple[float, tuple, str]:
    """Gap (mm), unit contact normal on the peg and the piece touched, for the rounding centre."""
    ca, sa = math.cos(p.chamfer_angle), math.sin(p.chamfer_angle)
    x, z = side * centre[0] - 0.5 * p.hole_diameter, centre[1]  # mirrored, relative to E
    if x * sa + z * ca > 0:
        gap, normal, piece = -x * ca + z * sa - rho, (-ca, sa), "chamfer"
    elif z < 0:
        gap, normal, piece = -x - rho, (-1.0, 0.0), "one_point"
    else:
        length = math.hypot(x, z)
        gap, normal, piece = length - rho, (x / length, z / length), "edge"
    return gap, (side * normal[0], normal[1]), piece


def _wrench(p: Insertion, rho: float, side: int, s: float, u: float, theta: float):
    """Gap, contact point on the peg, force on the peg per unit normal force, piece and C, tip."""
    centre, tip = pose(p, s, u, theta)
    P = rounding_centre(p, rho, side, tip, theta)
    gap, nu, piece = profile(p, rho, side, P)
    t = (side * nu[1], -side * nu[0])  # t' = (nu'_z, -nu'_x) in real coordinates
    point = (P[0] - rho * nu[0], P[1] - rho * nu[1])
    return gap, point, (nu[0] + p.mu * t[0], nu[1] + p.mu * t[1]), piece, centre, tip


def _residual(p: Insertion, rho: float, side: int, s: float, y: np.ndarray) -> np.ndarray:
    u, theta, force = y[0], y[1] / p.peg_diameter, y[2] * p.kx
    gap, point, f, _, centre, _ = _wrench(p, rho, side, s, u, theta)
    fx = -p.kx * u + force * f[0]
    moment = -p.ktheta * (theta - p.angular_error) + force * cross((point[0] - centre[0], point[1] - centre[1]), f)
    return np.array([fx / p.kx, moment / (p.kx * p.peg_diameter), gap])


def _free_gaps(p: Insertion, rho: float, s: float) -> list[float]:
    centre, tip = pose(p, s, 0.0, p.angular_error)
    return [profile(p, rho, side, rounding_centre(p, rho, side, tip, p.angular_error))[0] for side in (-1, 1)]


def edge_on_side(p: Insertion, rho: float, tip, theta: float) -> bool:
    """An edge E penetrates the peg's straight side (more than rho above the tip along the axis)."""
    for k, (kind, _) in enumerate(CANDIDATES):
        if kind == "edge":
            gap, point, _, _, _ = contact(p, k, tip, theta)
            if gap < 0 and dot((point[0] - tip[0], point[1] - tip[1]), axes(theta)[0]) >= rho:
                return True
    return False


def crossing(p: Insertion, rho: float, depths) -> dict:
    """The rounded rim's way in at the increasing depths s (mm): free ('none'), on the chamfer,
    rolling over the edge. Stops (`handover`) at the first depth where the rounding is on the wall,
    a hole edge touches the peg's straight side or the other side's rounding touches too: the
    sharp tier's wall mapping (femcontact.families.insertion.metrics) is exact there.
    Arrays depth, Fz, Fx, M, theta (deg), phase and `handover` (that depth or None)."""
    if not 0.0 < rho < p.r:
        raise InputError(f"peg.corner_radius = {rho}: the rounding must lie in (0, r = {p.r})")
    out = {key: [] for key in ("depth", "Fz", "Fx", "M", "theta", "phase")}
    side, y, handover = None, None, None
    for s in depths:
        s = float(s)
        if side is None:
            gaps = _free_gaps(p, rho, s)
            if edge_on_side(p, rho, pose(p, s, 0.0, p.angular_error)[1], p.angular_error):
                handover = s
                break
            if min(gaps) >= 0:
                Fz, Fx, M, theta, phase = 0.0, 0.0, 0.0, p.angular_error, "none"
            else:
                side = -1 if gaps[0] < gaps[1] else 1
                y = np.array([0.0, p.angular_error * p.peg_diameter, 0.0])
        if side is not None:
            guess = y
            for method, options in (("hybr", {"xtol": 1e-13}), ("lm", {"xtol": 1e-15})):
                y = root(lambda v: _residual(p, rho, side, s, v), guess, method=method, options=options).x
                if np.all(np.isfinite(y)) and np.max(np.abs(_residual(p, rho, side, s, y))) <= 1e-10 * p.peg_diameter:
                    break
            else:
                raise RuntimeError(f"rounded rim: no sliding equilibrium found at s = {s} mm")
            u, theta, force = y[0], y[1] / p.peg_diameter, y[2] * p.kx
            _, _, f, phase, centre, tip = _wrench(p, rho, side, s, u, theta)
            other = rounding_centre(p, rho, -side, tip, theta)
            if (force < 0 or phase == "one_point" or profile(p, rho, -side, other)[0] < 0
                    or edge_on_side(p, rho, tip, theta)):
                handover = s
                break
            Fz, Fx = force * f[1], -p.kx * u
            M = -p.ktheta * (theta - p.angular_error) + cross((centre[0] - tip[0], centre[1] - tip[1]), (Fx, -Fz))
        for key, value in zip(out, (s, Fz, Fx, M, math.degrees(theta), phase)):
            out[key].append(value)
    out["handover"] = handover
    return out
