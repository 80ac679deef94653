"""Closed forms of compliant part mating (Whitney ch. 11): statics of a sliding interface,
the cantilever spring and the rigid-arm model of insertion force against depth.

Convention: the pin moves down (-y) to insert; alpha (rad) is the interface angle of the nose
at the contact, measured from the insertion axis (a taper's half-angle); phi = atan(mu). The
contact force on the pin has a lateral part F_lat (pushing the pin away from the spring)
and an axial part F_ax, positive along +y, i.e. against insertion (pushing the pin out).
Sliding on a flat interface, with N the normal force:

    insertion:  F_ax / F_lat = (sin a + mu cos a) / (cos a - mu sin a) = tan(a + phi)
    withdrawal: F_ax / F_lat = (sin a - mu cos a) / (cos a + mu sin a) = tan(a - phi)

(withdrawal: positive = the spring ejects the pin, negative = it must be pulled). Insertion
is impossible (the spring's apex sticks on the nose and is pushed along its length: the pin
jams) when the force needed lies inside the friction cone, a + phi >= 90 deg.

The spring is a cantilever of length L and thickness h (width b out of plane): lateral tip
stiffness k = 3 E I / L^3 = E b h^3 / (4 L^3). Its contact apex sits e = h/2 + pad to the pin's
side of its axis, so the axial contact force F_ax bends it towards the pin with the moment
F_ax e; at the tip that is worth 1.5 e / L times F_ax as a lateral force (M L^2 / 2EI against
F L^3 / 3EI). The reduced (rigid-arm) model keeps the spring's stiffness k and this coupling:

    k delta = F_lat - 1.5 (e/L) F_ax,      delta = r(z) - r_apex (the nose's lateral rise),

where the apex, rising by 1.5 (e/L) delta as the spring's end turns, meets the nose at z; so F_lat = k delta / (1 - 1.5 (e/L) tan(a +- phi)); the pin jams where 1.5 (e/L) tan(a + phi) >= 1,
i.e. before the friction cone alone says so. (Whitney's rigid arm pivoting at the root gives
the factor 1 instead of 1.5.)
"""
import math

import numpy as np


def force_ratio(alpha, mu: float, withdrawal: bool = False):
    """F_ax / F_lat of a sliding flat interface (alpha in rad), insertion or withdrawal."""
    phi = math.atan(mu)
    return np.tan(np.asarray(alpha) - phi if withdrawal else np.asarray(alpha) + phi)


def jams_by_friction_cone(alpha, mu: float) -> np.ndarray:
    """Whitney's condition: the insertion force lies inside the friction cone (alpha in rad)."""
    return np.asarray(alpha) + math.atan(mu) >= math.pi / 2


def cantilever_stiffness(E: float, thickness: float, length: float, width: float = 1.0) -> float:
    """Lateral tip stiffness 3 E I / L^3 (N/mm) of a cantilever, I = width h^3 / 12."""
    return E * width * thickness ** 3 / (4 * length ** 3)


def timoshenko_stiffness(E: float, nu: float, thickness: float, length: float, width: float = 1.0) -> float:
    """Tip stiffness (N/mm) with shear deflection: 1 / (L^3 / 3EI + L / (kappa G A)), kappa = 5/6."""
    G, area = E / (2 * (1 + nu)), width * thickness
    bending = 1 / cantilever_stiffness(E, thickness, length, width)
    return 1 / (bending + length / (5 / 6 * G * area))


def coupling(spring: dict) -> float:
    """1.5 e / L: lateral tip force equivalent to a unit axial force at the apex."""
    e = spring["thickness"] / 2 + spring["pad_height"]
    return 1.5 * e / spring["length"]


def jams(alpha, mu: float, couple: float) -> np.ndarray:
    """Jam condition of the reduced model: couple * tan(alpha + phi) >= 1 (or alpha + phi >= 90 deg)."""
    total = np.asarray(alpha) + math.atan(mu)
    return (total >= math.pi / 2) | (couple * np.tan(np.minimum(total, math.pi / 2 - 1e-12)) >= 1)


def rigid_arm_forces(nose, r_apex: float, k: float, mu: float, couple: float, depth, withdrawal: bool = False):
    """(F_lat, F_ax) (N) of the reduced model against the pin's depth d past first touch (mm).

    `nose`: geometry.snap_fit.Nose. The spring's end turns as it deflects, so its apex (offset e
    from the axis) rises by 1.5 (e/L) delta = couple * delta (the kinematic twin of the force
    coupling): the apex meets the nose at z = z_touch + d + couple * delta, where z_touch is the
    nose's height at radius r_apex, and delta = r(z) - r_apex is found by fixed-point iteration.
    NaN where the model jams."""
    depth = np.asarray(depth, float)
    z_touch = nose.depth_at(r_apex)
    delta = np.zeros_like(depth)
    for _ in range(200):
        z = np.clip(z_touch + depth + couple * delta, 0.0, nose.pin_length)
        delta = np.where(depth > 0, nose.radius(z) - r_apex, 0.0)
    on_nose = z < nose.length
    alpha = np.where(on_nose, nose.slope_angle(np.minimum(z, nose.length * (1 - 1e-9))), 0.0)
    phi = math.atan(mu)
    angle = alpha - phi if withdrawal else alpha + phi
    denominator = 1 - couple * np.tan(angle)
    lateral = np.where(denominator > 0, k * delta / np.where(denominator > 0, denominator, 1.0), np.nan)
    return lateral, lateral * np.tan(angle)


def elastica_tip_force(E: float, thickness: float, length: float, offset: float, deflection: float,
                       width: float = 1.0) -> float:
    """Lateral force P (N) that moves the apex of a clamped elastica (inextensible, no shear) by
    `deflection` (mm) when P stays perpendicular to the undeformed axis and acts at an apex
    `offset` (mm) from the free end's axis on the side P comes from, carried rigidly by the end:
    EI theta' = P (Y - y(s)) with Y = y(L) + offset sin(theta_L) the apex height, and the apex
    moves by x(L) + offset (1 - cos theta_L). Solved by shooting (scipy)."""
    from scipy.integrate import solve_ivp
    from scipy.optimize import brentq

    EI = E * width * thickness ** 3 / 12

    def end(P, Y):
        def rhs(s, state):
            return [math.sin(state[2]), math.cos(state[2]), P * (Y - state[1]) / EI]

        return solve_ivp(rhs, (0, length), [0.0, 0.0, 0.0], rtol=1e-11, atol=1e-13).y[:, -1]

    def shoot(P):
        """Apex deflection for load P, the apex height Y found by a root search."""
        def mismatch(Y):
            x, y, theta = end(P, Y)
            return Y - y - offset * math.sin(theta)

        Y = brentq(mismatch, 0.0, length + offset, xtol=1e-13 * length)
        x, y, theta = end(P, Y)
        return x + offset * (1 - math.cos(theta))

    linear = cantilever_stiffness(E, thickness, length, width) * deflection
    return brentq(lambda P: shoot(P) - deflection, 0.7 * linear, 2.0 * linear, xtol=1e-12 * linear)
