"""Compliant insertion (Whitney, Mechanical Assemblies ch. 10; reference §4): the FE tier's metrics.

A rigid peg on a `compliant_support` descends into a chamfered hole. Each history row becomes
one point of the force history, in the analytic tier's conventions (femcontact.references.whitney):

- depth s (mm): the tip's depth below the lower edge of the hole chamfer had the support no axial
  compliance, s = l_d0 - (gripper_y + q_y) - h_c (l_d0: the initial insertion depth, q_y the
  compliance centre's axial deflection from the gripper, h_c the chamfer height): the analytic
  tier's support is rigid along the axis; `gripper_depth` leaves q_y out;
- Fz (N): insertion force, the support pushing the peg down (-support_Fy); Fx (N): the support's
  lateral force on the peg; M (N*mm): the support's moment on the peg about its tip;
- phase: from the contact zones A (x < 0) and B (x > 0): none; one zone touched by the peg's tip
  corner (`corner_contacts`) still above the chamfer's lower edge, or less than half a contact
  element below it (the corner rounding the hole's edge node): 'chamfer'; one zone otherwise:
  'one_point';
  both zones: 'two_point', with l (mm) from the tip to the edge contact (the higher zone force
  centre) along the peg. A zone is in contact when its force exceeds `CONTACT_FLOOR` of
  the largest zone force of the run.

Metrics: `two_point_onset` (the new zone's force extrapolated linearly to zero over the first
two two-point rows, kept inside the increment where it appeared), `peak_force`/`peak_depth`
(largest Fz at s >= 0 after the chamfer), `chamfer_peak_force`, `jammed` (the insertion force runs away:
dFz/ds over `JAM_WINDOW` of gripper travel exceeds `JAM_SLOPE` K_x, or the scene's stop
condition ended the run;
`jam_depth` the first such depth). Measured on studies/insertion.toml: sliding insertions rise
at most 1.8 K_x (the chamfer), the jammed case at 7.3 K_x in its first jammed increment and over 100 K_x
in the next, so 5 K_x separates them;
`wedged` (a two-point row whose contact points lie inside each other's friction cones: the
line joining the zone force centres within atan(mu) of the wall normal and of the peg's side
normal, as in the analytic tier).
"""
import math

import numpy as np

from geometry.placement import chamfer_height

CONTACT_FLOOR = 1e-4
JAM_SLOPE = 5.0
JAM_WINDOW = 0.05  # mm


def force_history(scene: dict, history: list[dict]) -> dict:
    """Depth, Fz, Fx, M, tilt (deg) and phase of every row (analytic tier's conventions)."""
    peg, hole, support = scene["peg"], scene["hole"], scene["support"]
    h_c = chamfer_height(hole["chamfer_width"], hole["chamfer_angle"])
    r, lg = peg["width"] / 2, support["compliance_centre"]
    h_contact = scene["mesh"]["contact_size"] or 0.0
    largest = max([max(row["contact_A_force"], row["contact_B_force"]) for row in history] + [0.0])
    floor = max(CONTACT_FLOOR * largest, 1e-12)
    out = {key: [] for key in ("depth", "gripper_depth", "Fz", "Fx", "M", "theta", "phase", "force_A", "force_B", "l")}
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
            on_corner = row.get("corner_contacts", 1) > 0
            phase = "chamfer" if on_corner and corner_y > -h_c - h_contact / 2 else "one_point"
        out["depth"].append(peg["insertion_depth"] - row["gripper_y"] - row["support_qy"] - h_c)
        out["gripper_depth"].append(peg["insertion_depth"] - row["gripper_y"] - h_c)
        out["Fz"].append(Fz)
        out["Fx"].append(Fx)
        out["M"].append(M)
        out["theta"].append(row["tilt_deg"])
        out["phase"].append(phase)
        # two-point: l from the tip to the edge contact (the higher zone centre) along the peg
        higher = max(row["contact_A_y"], row["contact_B_y"]) if phase == "two_point" else math.nan
        out["l"].append((higher - row["tip_y"]) / math.cos(theta))
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


def jam_depth(scene: dict, curve: dict) -> float | None:
    """First gripper depth (mm) where dFz/ds, over at least `JAM_WINDOW` of gripper travel, exceeds
    JAM_SLOPE K_x (s of the gripper: a jammed peg stops while the gripper goes on), or None. The
    window keeps cut increments (a few micrometres) from turning noise into slope."""
    from femcontact.effects.compliant_support import stiffness_matrix

    limit = JAM_SLOPE * stiffness_matrix(scene)[0, 0]
    depth, Fz = curve["gripper_depth"], curve["Fz"]
    for i in range(len(depth)):
        j = next((j for j in range(i + 1, len(depth)) if depth[j] >= depth[i] + JAM_WINDOW), None)
        if j is not None and (Fz[j] - Fz[i]) / (depth[j] - depth[i]) > limit:
            return float(depth[j])
    return None


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
    """The metrics above (2-D; a 3-D run reports its wall time only, its phases are not classified yet)."""
    scene, history = simulation.scene, simulation.history
    if scene["dim"] != 2:
        return {"analytic": False, "wall_time_s": float(sum(simulation.timings.values()))}
    curve = force_history(scene, history)
    depth, Fz = np.array(curve["depth"]), np.array(curve["Fz"])
    inside = (depth >= 0) & np.array([ph != "chamfer" for ph in curve["phase"]])
    out = {"two_point_onset": two_point_onset(curve)}
    if inside.any():
        i = int(np.argmax(np.where(inside, Fz, -np.inf)))
        out["peak_force"], out["peak_depth"] = float(Fz[i]), float(depth[i])
    else:
        out["peak_force"], out["peak_depth"] = None, None
    chamfer = [f for f, ph in zip(curve["Fz"], curve["phase"]) if ph == "chamfer"]
    out["chamfer_peak_force"] = float(max(chamfer)) if chamfer else None
    out["jam_depth"] = jam_depth(scene, curve)
    out["stopped"] = bool(simulation.stopped)
    out["jammed"] = out["jam_depth"] is not None or out["stopped"]
    mu = scene["contact"]["mu"] if "friction" in scene["effects"] else 0.0
    out["wedged"] = any(ph == "two_point" and inside_cones(row, mu) for row, ph in zip(history, curve["phase"]))
    out["final_depth"] = float(depth[-1])
    for phase in ("chamfer", "one_point", "two_point"):
        out[f"{phase}_increments"] = sum(ph == phase for ph in curve["phase"])
    out["lambda_onset"] = (out["two_point_onset"] / (mu * scene["peg"]["width"])
                           if out["two_point_onset"] is not None and mu > 0 else None)
    out.update(analytic_metrics(scene, curve))
    out["wall_time_s"] = float(sum(simulation.timings.values()))
    return out


# ---- the analytic tier on the same scene (femcontact.references.whitney) ----------------------
PHASES = ("chamfer", "one_point", "two_point")


def analytic_problem(scene: dict):
    """The scene as a `whitney.Insertion` (2-D, diagonal support), or None when the analytic tier
    does not describe it (3-D, a coupled stiffness, no chamfer)."""
    from femcontact.effects.compliant_support import stiffness_matrix
    from femcontact.references import whitney

    K = stiffness_matrix(scene)
    if scene["dim"] != 2 or np.count_nonzero(K - np.diag(np.diag(K))) or scene["hole"]["chamfer_width"] <= 0:
        return None
    peg, hole = scene["peg"], scene["hole"]
    mu = scene["contact"]["mu"] if "friction" in scene["effects"] else 0.0
    return whitney.Insertion(peg["width"], hole["width"], mu, K[0, 0], K[2, 2], scene["support"]["compliance_centre"],
                             peg["offset"], math.radians(peg["tilt"]), hole["chamfer_width"],
                             math.radians(hole["chamfer_angle"]))


def analytic_curve(scene: dict, depth_max: float, points: int = 201) -> dict | None:
    """The analytic force history to depth_max (mm), or None (see analytic_problem)."""
    from femcontact.errors import InputError
    from femcontact.references import whitney

    problem = analytic_problem(scene)
    if problem is None:
        return None
    try:
        return whitney.insertion(problem, depth_max, points)
    except InputError:
        return None


def compare(curve: dict, analytic: dict) -> dict:
    """Per phase: the largest |FE - analytic| of Fz and Fx over the FE rows of that phase lying within
    the analytic phase's depth range (interpolated inside it), relative to the largest analytic |Fz|
    (|Fx|) of that phase; and the fraction of rows in contact whose phase the analytic state at the
    nearest depth shares."""
    a_depth = np.array(analytic["depth"])
    out, agree, counted = {}, 0, 0
    nearest = [int(np.argmin(np.abs(a_depth - s))) for s in curve["depth"]]
    for phase in PHASES:
        same = np.array([ph == phase for ph in analytic["phase"]])
        if not same.any():
            out.update({f"{q}_error_{phase}": None for q in ("fz", "fx")})
            continue
        depths = a_depth[same]  # interpolate inside the phase only: the forces jump between phases
        rows = [i for i, ph in enumerate(curve["phase"]) if ph == phase and depths[0] <= curve["depth"][i] <= depths[-1]]
        for quantity in ("Fz", "Fx"):
            values = np.array(analytic[quantity])[same]
            scale = float(np.abs(values).max())
            errors = [abs(curve[quantity][i] - np.interp(curve["depth"][i], depths, values)) for i in rows]
            out[f"{quantity.lower()}_error_{phase}"] = float(max(errors) / scale) if errors and scale > 0 else None
    for i, ph in enumerate(curve["phase"]):
        if ph != "none" and a_depth[0] <= curve["depth"][i] <= a_depth[-1]:
            counted += 1
            agree += analytic["phase"][nearest[i]] == ph
    out["phase_agreement"] = agree / counted if counted else None
    return out


def analytic_metrics(scene: dict, curve: dict) -> dict:
    """The analytic tier's onset, peaks, wedging and jamming, and the comparison per phase."""
    analytic = analytic_curve(scene, max(curve["depth"][-1], 1e-3))
    if analytic is None:
        return {"analytic": False}
    out = {"analytic": True, "analytic_two_point_onset": analytic["two_point_onset"],
           "analytic_peak_force": analytic["peak_force"], "analytic_peak_depth": analytic["peak_depth"],
           "analytic_chamfer_peak_force": analytic["chamfer_peak_force"],
           "analytic_jams": analytic["jams"], "analytic_jam_depth": analytic["jam_depth"],
           "analytic_wedging": analytic["wedging_possible"]}
    out.update(compare(curve, analytic))
    return out
