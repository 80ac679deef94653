"""Compliant insertion (Whitney, Mechanical Assemblies ch. 10): the FE tier's metrics.

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
  'one_point'; a tip rim rounded with radius rho (`peg.corner_radius`): from the rounding's
  centre P on the touching side and the chamfer's lower edge E there, 'chamfer' while P projects
  onto the chamfer line above E (the rounding on the cone), 'edge' while P lies above E both
  vertically and along the peg axis (the rounding rolls over E), 'one_point' after (the rounding
  on the wall or E on the straight side; as in references/rounded_rim.py);
  both zones: 'two_point', with l (mm) from the tip to the edge contact (the higher zone force
  centre) along the peg. A zone is in contact when its force exceeds `CONTACT_FLOOR` of
  the largest zone force of the run.

Metrics: `two_point_onset` (the new zone's force extrapolated linearly to zero over the first
two two-point rows, kept inside the increment where it appeared), `peak_force`/`peak_depth`
(largest Fz at s >= 0 after the chamfer and edge phases), `chamfer_peak_force` (over both), `jammed` (the insertion force runs away:
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
from femcontact.config.scene import friction_coefficient

CONTACT_FLOOR = 1e-4
JAM_SLOPE = 5.0
JAM_WINDOW = 0.05  # mm


def in_plane(scene: dict, row: dict) -> tuple[str, float, float]:
    """The axial axis name ('y' in 2-D, 'z' in 3-D), the tilt (deg, top towards -x positive) and
    the support's moment about C in the insertion plane (N*mm, counter-clockwise in (x, axial)):
    2-D M_z; 3-D the x-z plane, i.e. -M_y."""
    if scene["dim"] == 2:
        return "y", row["tilt_deg"], row["support_Mz"]
    return "z", row["tilt_xz_deg"], -row["support_My"]


def force_history(scene: dict, history: list[dict]) -> dict:
    """Depth, Fz, Fx, M, tilt (deg) and phase of every row (analytic tier's conventions; in 3-D
    in the x-z plane, where the lateral and angular errors lie)."""
    peg, hole, support = scene["peg"], scene["hole"], scene["support"]
    h_c = chamfer_height(hole["chamfer_width"], hole["chamfer_angle"])
    r, lg, rho = peg["width"] / 2, support["compliance_centre"], peg["corner_radius"]
    a = math.radians(hole["chamfer_angle"])
    h_contact = scene["mesh"]["contact_size"] or 0.0
    largest = max([max(row["contact_A_force"], row["contact_B_force"]) for row in history] + [0.0])
    floor = max(CONTACT_FLOOR * largest, 1e-12)
    out = {key: [] for key in ("depth", "gripper_depth", "Fz", "Fx", "M", "theta", "phase", "force_A", "force_B", "l")}
    for row in history:
        ax, tilt_deg, M_C = in_plane(scene, row)
        theta = math.radians(tilt_deg)
        Fz, Fx = -row[f"support_F{ax}"], row["support_Fx"]
        # moment about the tip: M_C + (C - tip) x F, C - tip = L_g (-sin theta, cos theta), F = (Fx, -Fz)
        M = M_C + lg * (-math.sin(theta)) * (-Fz) - lg * math.cos(theta) * Fx
        touching = [zone for zone in "AB" if row[f"contact_{zone}_force"] > floor]
        side = -1.0 if touching[:1] == ["A"] else 1.0  # of the one zone touched
        if not touching:
            phase = "none"
        elif len(touching) == 2:
            phase = "two_point"
        elif rho > 0:  # where the rounding's centre P on the touching side lies from the edge E
            axis, normal = (-math.sin(theta), math.cos(theta)), (math.cos(theta), math.sin(theta))
            P = [row[f"tip_{c}"] + side * (r - rho) * normal[k] + rho * axis[k] for k, c in enumerate(("x", ax))]
            PE = (P[0] - side * hole["width"] / 2, P[1] + h_c)
            on_cone = PE[0] * side * math.sin(a) + PE[1] * math.cos(a) > 0
            on_rounding = PE[1] > 0 and PE[0] * axis[0] + PE[1] * axis[1] > 0  # not yet on the wall or side
            phase = "chamfer" if on_cone else "edge" if on_rounding else "one_point"
        else:
            corner_y = row[f"tip_{ax}"] + side * r * math.sin(theta)
            on_corner = row.get("corner_contacts", 1) > 0
            phase = "chamfer" if on_corner and corner_y > -h_c - h_contact / 2 else "one_point"
        out["depth"].append(peg["insertion_depth"] - row[f"gripper_{ax}"] - row[f"support_q{ax}"] - h_c)
        out["gripper_depth"].append(peg["insertion_depth"] - row[f"gripper_{ax}"] - h_c)
        out["Fz"].append(Fz)
        out["Fx"].append(Fx)
        out["M"].append(M)
        out["theta"].append(tilt_deg)
        out["phase"].append(phase)
        # two-point: l from the tip to the edge contact (the higher zone centre) along the peg
        higher = max(row[f"contact_A_{ax}"], row[f"contact_B_{ax}"]) if phase == "two_point" else math.nan
        out["l"].append((higher - row[f"tip_{ax}"]) / math.cos(theta))
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
    from femcontact.physics.support import stiffness_matrix

    limit = JAM_SLOPE * stiffness_matrix(scene)[0, 0]
    depth, Fz = curve["gripper_depth"], curve["Fz"]
    for i in range(len(depth)):
        j = next((j for j in range(i + 1, len(depth)) if depth[j] >= depth[i] + JAM_WINDOW), None)
        if j is not None and (Fz[j] - Fz[i]) / (depth[j] - depth[i]) > limit:
            return float(depth[j])
    return None


def inside_cones(scene: dict, row: dict, mu: float) -> bool:
    """The two zone force centres lie inside each other's friction cones (wall normal x, peg
    side normal (cos theta, sin theta)), in the insertion plane."""
    ax, tilt_deg, _ = in_plane(scene, row)
    a = np.array([row["contact_A_x"], row[f"contact_A_{ax}"]], dtype=float)
    b = np.array([row["contact_B_x"], row[f"contact_B_{ax}"]], dtype=float)
    if not np.all(np.isfinite(np.r_[a, b])) or np.allclose(a, b):
        return False
    e = (b - a) / np.linalg.norm(b - a)
    theta = math.radians(tilt_deg)
    cos_cone = 1.0 / math.hypot(1.0, mu)
    return bool(abs(e[0]) >= cos_cone and abs(e @ np.array([math.cos(theta), math.sin(theta)])) >= cos_cone)


def in_hole_peak(curve: dict) -> tuple[float | None, float | None]:
    """Largest Fz (N) at s >= 0 outside the chamfer and edge phases and its depth s (mm), or (None, None)."""
    depth, Fz = np.array(curve["depth"]), np.array(curve["Fz"])
    inside = (depth >= 0) & np.array([ph not in ("chamfer", "edge") for ph in curve["phase"]])
    if not inside.any():
        return None, None
    i = int(np.argmax(np.where(inside, Fz, -np.inf)))
    return float(Fz[i]), float(depth[i])


def insertion_metrics(simulation) -> dict:
    """The metrics above (3-D: in the x-z plane)."""
    scene, history = simulation.scene, simulation.history
    curve = force_history(scene, history)
    depth = np.array(curve["depth"])
    out = {"two_point_onset": two_point_onset(curve)}
    out["peak_force"], out["peak_depth"] = in_hole_peak(curve)
    chamfer = [f for f, ph in zip(curve["Fz"], curve["phase"]) if ph in ("chamfer", "edge")]
    out["chamfer_peak_force"] = float(max(chamfer)) if chamfer else None
    out["jam_depth"] = jam_depth(scene, curve)
    out["stopped"] = bool(simulation.stopped)
    out["jammed"] = out["jam_depth"] is not None or out["stopped"]
    mu = friction_coefficient(scene)
    out["wedged"] = any(ph == "two_point" and inside_cones(scene, row, mu) for row, ph in zip(history, curve["phase"]))
    out["final_depth"] = float(depth[-1])
    for phase in PHASES:
        out[f"{phase}_increments"] = sum(ph == phase for ph in curve["phase"])
    out["lambda_onset"] = (out["two_point_onset"] / (mu * scene["peg"]["width"])
                           if out["two_point_onset"] is not None and mu > 0 else None)
    out.update(analytic_metrics(scene, curve))
    out["wall_time_s"] = float(sum(simulation.timings.values()))
    return out


# ---- the analytic tier on the same scene (femcontact.references.whitney) ----------------------
PHASES = ("chamfer", "edge", "one_point", "two_point")


def analytic_problem(scene: dict):
    """The scene as a `whitney.Insertion` and the depth offset (mm) of the analytic tier's tip below
    the real one, or None when the analytic tier does not describe it (a support coupled in the
    insertion plane, no chamfer). 3-D: the x-z plane (K_x = K[x, x], K_theta = K[ry, ry]).

    A tip rim rounded with radius rho (`peg.corner_radius`) is the analytic tier's sharp peg of the
    same width with its tip rho higher (at the rounding's centres): the rounding touches a wall
    where that sharp corner does, to rho (1 - cos theta), and the edge touches the same straight
    side; so L_g - rho, eps0 - rho sin theta0, and depths rho cos theta0 deeper. On the chamfer
    the rounding touches elsewhere: `analytic_curve` takes the crossing from
    femcontact.references.rounded_rim instead."""
    from femcontact.physics.support import stiffness_matrix
    from femcontact.references import whitney

    K = stiffness_matrix(scene)
    plane = [0, 1, 2] if scene["dim"] == 2 else [0, 2, 4]
    K_plane = K[np.ix_(plane, plane)]
    if np.count_nonzero(K_plane - np.diag(np.diag(K_plane))) or scene["hole"]["chamfer_width"] <= 0:
        return None
    peg, hole = scene["peg"], scene["hole"]
    mu = friction_coefficient(scene)
    rho, theta0 = peg["corner_radius"], math.radians(peg["tilt"])
    problem = whitney.Insertion(peg["width"], hole["width"], mu, K_plane[0, 0], K_plane[2, 2],
                                scene["support"]["compliance_centre"] - rho, peg["offset"] - rho * math.sin(theta0),
                                theta0, hole["chamfer_width"], math.radians(hole["chamfer_angle"]))
    return problem, rho * math.cos(theta0)


def analytic_curve(scene: dict, depth_max: float, points: int = 201) -> dict | None:
    """The analytic force history to depth_max (mm), or None (see analytic_problem); depths are
    those of the scene's tip. A rounded rim: the crossing (free, 'chamfer', 'edge') from
    rounded_rim.crossing on the real peg, then the sharp tier's rows after its chamfer phase;
    the scalars from the sharp tier, the chamfer peak (crossing peak) from the crossing."""
    from dataclasses import replace

    from femcontact.errors import InputError
    from femcontact.references import rounded_rim, whitney

    described = analytic_problem(scene)
    if described is None:
        return None
    problem, offset = described
    try:
        curve = whitney.insertion(problem, depth_max - offset, points)
    except InputError:
        return None
    curve["depth"] = [s + offset for s in curve["depth"]]
    for key in ("two_point_onset", "peak_depth", "jam_depth"):
        curve[key] = None if curve[key] is None else curve[key] + offset
    rho = scene["peg"]["corner_radius"]
    if rho <= 0:
        return curve
    real = replace(problem, lg=problem.lg + rho, lateral_error=scene["peg"]["offset"])
    way_in = rounded_rim.crossing(real, rho, np.linspace(curve["depth"][0], depth_max, points))
    after = [i for i, s in enumerate(curve["depth"]) if way_in["handover"] is not None and s >= way_in["handover"]]
    while after and curve["phase"][after[0]] == "chamfer":  # the sharp corner still above E: not yet
        after.pop(0)
    keys = ("depth", "Fz", "Fx", "M", "theta", "phase")
    out = {key: way_in[key] + [curve[key][i] for i in after] for key in keys}
    out.update({key: curve[key] for key in ("two_point_onset", "peak_force", "peak_depth", "wedging_possible",
                                             "jams", "jam_depth")})
    crossing = [f for f, ph in zip(way_in["Fz"], way_in["phase"]) if ph in ("chamfer", "edge")]
    out["chamfer_peak_force"] = max(crossing) if crossing else None
    return out


def compare(curve: dict, analytic: dict) -> dict:
    """Per phase: the largest |FE - analytic| of Fz and Fx over the FE rows of that phase lying within
    the analytic phase's depth range (interpolated inside it), relative to the largest analytic |Fz|
    (|Fx|) of that phase; and the fraction of rows in a phase of PHASES whose phase the analytic
    state at the nearest depth shares."""
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
        if ph in PHASES and a_depth[0] <= curve["depth"][i] <= a_depth[-1]:
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


# ---- `make accuracy`: the 2-D insertion's accuracy against wall time -----------------------------
ACCURACY_RESOLUTIONS = (0.5, 0.7, 1.0, 1.4)
ACCURACY_INCREMENTS = (26, 52, 104)
ACCURACY_RTOLS = (1e-6, 1e-9, 1e-11)
ACCURACY_KEYS = ("peak_force", "two_point_onset")


def accuracy_case(label: str, knob: str, overrides=()) -> dict:
    """One run of scenes/insertion_2d.toml with `overrides`: the in-hole peak force (N), the
    two-point onset (mm) and the wall time (s: mesh, forms, solve and measurement)."""
    import time

    from femcontact.families import load_scene
    from femcontact.families.repository import SCENES
    from femcontact.solver.stepping import Simulation

    start = time.perf_counter()
    scene = load_scene(SCENES / "insertion_2d.toml", list(overrides))
    simulation = Simulation(scene)
    simulation.run()
    curve = force_history(scene, simulation.history)
    peak, _ = in_hole_peak(curve)
    return {"knob": knob, "setting": label, "dofs": simulation.dofs, "wall_time": time.perf_counter() - start,
            "newton_iterations": sum(r["newton_iterations"] for r in simulation.history),
            "increments": len(simulation.history), "peak_force": peak, "two_point_onset": two_point_onset(curve)}


def accuracy_rows() -> tuple[list[dict], list[str]]:
    """`make accuracy` rows of the 2-D insertion (scenes/insertion_2d.toml): the in-hole peak force
    and the two-point onset depth against mesh resolution (errors against a Richardson extrapolation
    of the three finest resolutions, else the finest), against the number of load increments at
    resolution 1 and against Newton's rtol (errors against the finest setting of that knob). The
    scene's own setting (resolution 1, 52 increments, rtol 1e-9) is run once and shown in each knob."""
    from femcontact.references.richardson import richardson

    accuracy_case("warm-up", "", ["mesh.resolution=0.5", "steps.0.increments=3", "steps.0.support_motion.y=-1.2"])
    mesh = [accuracy_case(f"resolution {r:g}", "mesh (P1)", [f"mesh.resolution={r}"]) for r in ACCURACY_RESOLUTIONS]
    base = mesh[ACCURACY_RESOLUTIONS.index(1.0)]  # the scene as it is: 52 increments, rtol 1e-9

    def knob(label, name, override, is_base):
        return dict(base, knob=name, setting=label) if is_base else accuracy_case(label, name, [override])

    steps = [knob(f"{n} increments", "load increments", f"steps.0.increments={n}", n == 52) for n in ACCURACY_INCREMENTS]
    rtols = [knob(f"rtol {t:g}", "Newton rtol", f"solver.rtol={t}", t == 1e-9) for t in ACCURACY_RTOLS]
    notes = []
    for key in ACCURACY_KEYS:
        finest = [row[key] for row in mesh[-3:]]
        if None in finest:
            reference, how = mesh[-1][key], "the finest resolution (a value is missing)"
        else:
            reference, order = richardson(finest, ACCURACY_RESOLUTIONS[-1] / ACCURACY_RESOLUTIONS[-2])
            how = (f"Richardson extrapolation of resolutions {', '.join(f'{r:g}' for r in ACCURACY_RESOLUTIONS[-3:])} "
                   f"(observed order {order:.2f})" if math.isfinite(order) and order > 0 else
                   f"the finest resolution (no Richardson: the three finest values do not converge "
                   f"monotonically, observed order {order:.2f})")
        references = [(mesh, reference), (steps, steps[-1][key]), (rtols, rtols[-1][key])]
        for rows, value in references:
            for row in rows:
                ok = row[key] is not None and value
                row[f"error_{key}"] = abs(row[key] / value - 1) if ok else float("nan")
        notes.append(f"Reference for {key}: mesh rows {reference if reference is None else f'{reference:.6g}'} from {how}; "
                     f"increment rows the {ACCURACY_INCREMENTS[-1]} increments, rtol rows rtol {ACCURACY_RTOLS[-1]:g}.")
    return mesh + steps + rtols, notes
