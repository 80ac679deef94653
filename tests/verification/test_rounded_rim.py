"""The chamfer crossing of a rounded tip rim (femcontact/references/rounded_rim.py) against
independent checks: the sharp tier in the limit rho -> 0, closed forms on the chamfer and on the
edge for a peg that cannot tilt (K_theta -> infinity), and the sharp tier on the chamfer line moved
rho into the hole (the rounding's centre as the sharp corner) without friction."""
import math
from dataclasses import replace

import numpy as np
import pytest

from femcontact.references import rounded_rim, whitney

# d 10, D 10.1, mu 0.1, the Draper-like RCC (K_x 7.02 N/mm, K_theta 53400 N*mm/rad), L_g 20,
# eps0 0.6 mm, theta0 0, chamfer 1 mm at 45 deg
BASE = whitney.Insertion(10.0, 10.1, 0.1, 7.02, 53400.0, 20.0, 0.6, 0.0, 1.0, math.radians(45.0))


def test_vanishing_rounding_is_the_sharp_corner():
    """rho = 1e-5 mm: Fz and Fx on the chamfer equal the sharp tier's to 1e-4 relative (the
    rounding moves the contact by rho)."""
    depths = np.linspace(-0.41, 0.19, 13)
    rounded = rounded_rim.crossing(BASE, 1e-5, depths)
    sharp = {round(st.s, 9): st for st in (whitney.solve_depth(BASE, float(s)) for s in depths)}
    compared = 0
    for s, fz, fx, phase in zip(rounded["depth"], rounded["Fz"], rounded["Fx"], rounded["phase"]):
        if phase == "chamfer" and sharp[round(s, 9)].phase == "chamfer":
            compared += 1
            assert fz == pytest.approx(sharp[round(s, 9)].Fz, rel=1e-4)
            assert fx == pytest.approx(sharp[round(s, 9)].Fx, rel=1e-4)
    assert compared >= 5


@pytest.mark.parametrize("mu", [0.0, 0.1])
def test_rigid_tilt_closed_forms_on_chamfer_and_edge(mu):
    """K_theta = 1e12: the peg only translates, so the rounding's centre P = (eps0 + u + r - rho,
    rho - s) lies rho from the chamfer line (u linear in s, Fz/Fx = (tan a + mu)/(1 - mu tan a))
    or rho from the edge E (P - E = rho (-cos phi, sin phi), Fz/Fx = (sin phi + mu cos phi) /
    (cos phi - mu sin phi)); Fx = -K_x u. To 1e-7."""
    p = replace(BASE, ktheta=1e12, mu=mu)
    rho, a, half = 1.0, p.chamfer_angle, 0.5 * p.hole_diameter
    out = rounded_rim.crossing(p, rho, np.linspace(0.0, 1.2, 25))
    phases = set(out["phase"])
    assert {"chamfer", "edge"} <= phases and out["handover"] is not None
    for s, fz, fx, phase in zip(out["depth"], out["Fz"], out["Fx"], out["phase"]):
        z = rho - s  # the centre's height above E
        if phase == "chamfer":  # (x - half) (-cos a) + z sin a = rho, x the centre's x
            x = half + (z * math.sin(a) - rho) / math.cos(a)
            ratio = whitney.chamfer_gain(a, mu)
        elif phase == "edge":
            phi = math.asin(z / rho)
            x = half - rho * math.cos(phi)
            ratio = (math.sin(phi) + mu * math.cos(phi)) / (math.cos(phi) - mu * math.sin(phi))
        else:
            continue
        u = x - (p.lateral_error + p.r - rho)
        assert fx == pytest.approx(-p.kx * u, rel=1e-7, abs=1e-9)
        assert fz == pytest.approx(fx * ratio, rel=1e-7, abs=1e-9)


def test_frictionless_chamfer_is_the_sharp_tier_on_the_moved_chamfer_line():
    """mu = 0: on the chamfer the rounded peg is the sharp peg d - 2 rho whose corner is the
    rounding's centre (tip rho higher, L_g - rho) in the hole D - 2 rho whose chamfer line is moved
    rho inwards, meeting that hole's wall z_e = rho (1 - cos a)/sin a above E (chamfer width
    W + rho (1 - cos a)); depths shift by rho - z_e. Fz, Fx and the tilt agree to 1e-7."""
    p, rho = replace(BASE, mu=0.0, ktheta=3000.0), 1.0
    a = p.chamfer_angle
    z_e = rho * (1 - math.cos(a)) / math.sin(a)
    moved = replace(p, peg_diameter=p.peg_diameter - 2 * rho, hole_diameter=p.hole_diameter - 2 * rho,
                    lg=p.lg - rho, chamfer_width=p.chamfer_width + rho * (1 - math.cos(a)))
    out = rounded_rim.crossing(p, rho, np.linspace(0.0, 0.4, 9))
    compared = 0
    for s, fz, fx, theta, phase in zip(out["depth"], out["Fz"], out["Fx"], out["theta"], out["phase"]):
        if phase != "chamfer":
            continue
        state = whitney.solve_depth(moved, s - (rho - z_e))
        assert state.phase == "chamfer"
        compared += 1
        assert fz == pytest.approx(state.Fz, rel=1e-7) and fx == pytest.approx(state.Fx, rel=1e-7)
        assert theta == pytest.approx(math.degrees(state.theta), rel=1e-7)
    assert compared >= 4
