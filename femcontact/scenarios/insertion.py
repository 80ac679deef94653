"""Compliant insertion (Whitney, Mechanical Assemblies ch. 10; reference §4): the FE tier's metrics.

A rigid peg on a `compliant_support` descends into a chamfered hole. Each history row becomes
one point of the force history, in the analytic tier's conventions (femcontact.references.whitney):

- depth s (mm): the support's rest position of the tip below the lower edge of the hole chamfer,
  s = l_d0 - gripper_y - h_c (l_d0: the initial insertion depth, h_c the chamfer height);
- Fz (N): insertion force, the support pushing the peg down (-support_Fy); Fx (N): the support's
  lateral force on the peg; M (N*mm): the support's moment on the peg about its tip;
- phase: from the contact zones A (x < 0) and B (x > 0): none; one zone whose leading tip
  corner is still above the chamfer's lower edge: 'chamfer'; one zone otherwise: 'one_point';
  both zones: 'two_point'. A zone is in contact when its force exceeds `CONTACT_FLOOR` of
  the largest zone force of the run.

Metrics: `two_point_onset` (the new zone's force extrapolated linearly to zero over the first
two two-point rows, kept inside the increment where it appeared), `peak_force`/`peak_depth`
(largest Fz at s >= 0), `chamfer_peak_force`, `jammed` (the insertion force runs away: its
peak exceeds `JAM_RATIO` times the lateral force scale F_ref = K_x |eps0 + L_g theta0| +
K_theta |theta0| / r that corrects the initial errors; a sliding insertion needs about mu F_ref),
`wedged` (a two-point row whose contact points lie inside each other's friction cones: the
line joining the zone force centres within atan(mu) of the wall normal and of the peg's side
normal, as in the analytic tier).
"""
import math

import numpy as np

from geometry.placement import chamfer_height

CONTACT_FLOOR = 1e-4
JAM_RATIO = 5.0


def force_history(scene: dict, history: list[dict]) -> dict:
    """Depth, Fz, Fx, M, tilt (deg) and phase of every row (analytic tier's conventions)."""
    peg, hole, support = scene["peg"], scene["hole"], scene["support"]
    h_c = chamfer_height(hole["chamfer_width"], hole["chamfer_angle"])
    r, lg = peg["width"] / 2, support["compliance_centre"]
    largest = max([max(row["contact_A_force"], row["contact_B_force"]) for row in history] + [0.0])
    floor = max(CONTACT_FLOOR * largest, 1e-12)
    out = {key: [] for key in ("depth", "Fz", "Fx", "M", "theta", "phase", "force_A", "force_B")}
    for row in history:
        theta = math.radians(row["tilt_deg"])
        Fz, Fx = -row["support_Fy"], row["support_Fx"]
        # moment about the tip: M_C + (C - tip) x F, C - tip = L_g (-sin theta, cos theta), F = (Fx, -Fz)
        M = row["support_Mz"] + lg * (-math.sin(theta)) * (-Fz) - lg * math.cos(theta) * Fx
        touching = [zone for zone in "AB" if row[f"contact_{zone}_force"] > floor]
        if not touching:
            phase = "none"
        elif len(touching) == 2:
            phase = "two_point"
        else:
            side = -1.0 if touching[0] == "A" else 1.0
            corner_y = row["tip_y"] + side * r * math.sin(theta)
            phase = "chamfer" if corner_y > -h_c else "one_point"
        out["depth"].append(peg["insertion_depth"] - row["gripper_y"] - h_c)
        out["Fz"].append(Fz)
        out["Fx"].append(Fx)
        out["M"].append(M)
        out["theta"].append(row["tilt_deg"])
        out["phase"].append(phase)
        out["force_A"].append(row["contact_A_force"])
        out["force_B"].append(row["contact_B_force"])
    return out


def two_point_onset(curve: dict) -> float | None:
    """Depth (mm) where the second contact closes, or None without two-point contact."""
    phases, depth = curve["phase"], curve["depth"]
    first = next((i for i, ph in enumerate(phases) if ph == "two_point"), None)
    if first is None:
        return None
    if first == 0 or first + 1 >= len(phases) or phases[first + 1] != "two_point":
        return depth[first]
    before = phases[first - 1]
    new = "force_A" if before == "one_point" and curve["force_B"][first - 1] > curve["force_A"][first - 1] else "force_B"
    if before != "one_point":
        return depth[first]
    f0, f1 = curve[new][first], curve[new][first + 1]
    s0, s1 = depth[first], depth[first + 1]
    if f1 <= f0:
        return s0
    onset = s0 - f0 * (s1 - s0) / (f1 - f0)
    return float(min(max(onset, depth[first - 1]), s0))


def force_scale(scene: dict) -> float:
    """F_ref (N): the lateral support force that corrects the initial errors, K_x |eps0 + L_g theta0| +
    K_theta |theta0| / r (K from the support's diagonal)."""
    from femcontact.effects.compliant_support import stiffness_matrix

    K = stiffness_matrix(scene)
    peg, lg = scene["peg"], scene["support"]["compliance_centre"]
    theta0 = math.radians(peg["tilt"])
    kx, ktheta = K[0, 0], K[-1, -1] if scene["dim"] == 2 else K[4, 4]
    return float(kx * abs(peg["offset"] - lg * math.sin(theta0)) + ktheta * abs(theta0) / (peg["width"] / 2))


def inside_cones(row: dict, mu: float) -> bool:
    """The two zone force centres lie inside each other's friction cones (wall normal x, peg
    side normal (cos theta, sin theta))."""
    a = np.array([row["contact_A_x"], row["contact_A_y"]])
    b = np.array([row["contact_B_x"], row["contact_B_y"]])
    if not np.all(np.isfinite(np.r_[a, b])) or np.allclose(a, b):
        return False
    e = (b - a) / np.linalg.norm(b - a)
    theta = math.radians(row["tilt_deg"])
    cos_cone = 1.0 / math.hypot(1.0, mu)
    return bool(abs(e[0]) >= cos_cone and abs(e @ np.array([math.cos(theta), math.sin(theta)])) >= cos_cone)


def insertion_metrics(simulation) -> dict:
    scene, history = simulation.scene, simulation.history
    curve = force_history(scene, history)
    depth, Fz = np.array(curve["depth"]), np.array(curve["Fz"])
    inside = depth >= 0
    out = {"two_point_onset": two_point_onset(curve)}
    if inside.any():
        i = int(np.argmax(np.where(inside, Fz, -np.inf)))
        out["peak_force"], out["peak_depth"] = float(Fz[i]), float(depth[i])
    else:
        out["peak_force"], out["peak_depth"] = None, None
    chamfer = [f for f, ph in zip(curve["Fz"], curve["phase"]) if ph == "chamfer"]
    out["chamfer_peak_force"] = float(max(chamfer)) if chamfer else None
    out["force_scale"] = force_scale(scene)
    out["jammed"] = bool(Fz.max(initial=0.0) > JAM_RATIO * out["force_scale"])
    mu = scene["contact"]["mu"] if "friction" in scene["effects"] else 0.0
    out["wedged"] = any(ph == "two_point" and inside_cones(row, mu) for row, ph in zip(history, curve["phase"]))
    out["final_depth"] = float(depth[-1])
    for phase in ("chamfer", "one_point", "two_point"):
        out[f"{phase}_increments"] = sum(ph == phase for ph in curve["phase"])
    out["lambda_onset"] = (out["two_point_onset"] / (mu * scene["peg"]["width"])
                           if out["two_point_onset"] is not None and mu > 0 else None)
    out["wall_time_s"] = float(sum(simulation.timings.values()))
    return out
