"""Snap-fit metrics (Whitney ch. 11): insertion and withdrawal force against depth.

Signs (femcontact.references.snap_fit): the pin moves down to insert; the contact force on
the pin has an axial part F_ax, positive upwards (against insertion), and a lateral part
F_lat, the sum over the springs of the magnitude of each spring's lateral force. The 2-D
history is per mm of out-of-plane width; every force here (N) is multiplied by
`spring.width`. Depth is the pin's travel past the first touch of its nose on the apex
(travel less `peg.start_gap`).

- insertion_force = F_ax during the step `insert` (what the actuator pushes with),
  withdrawal_force = -F_ax during `withdraw` (what it pulls with; negative: the springs eject
  the pin), each against depth (lists), with lateral_force / withdrawal_lateral_force;
- final_contact_force: each spring's lateral force at the end of insertion (N);
- insertion_force_ratio / withdrawal_force_ratio: F_ax / F_lat averaged over the increments
  whose contact lies on the nose (not on the shank) and whose lateral force is above
  `RATIO_FLOOR` of its peak: on a flat taper, the statics tan(alpha +- phi);
- jammed, with `jam_reason` and `jam_depth` (mm, the first jammed increment): in some insertion
  increment (1) the apex of spring B is in contact with the nose and its force lies strictly
  inside the friction cone about the nose's normal, i.e. the apex sticks to the nose and is
  pushed along instead of sliding (`STICK_MARGIN`); or (2) the spring buckles: the axial force
  at its root exceeds the Euler load of a cantilever, pi^2 EI / (4 L^2) (`buckling_ratio`).
  Where no sliding equilibrium exists Newton cycles between stick and slip; the solver's last try
  of such an increment, every contact stuck first (`Simulation.locked_first_solve`), finds the
  stuck apex, which criterion 1 flags;
- max_insertion_slope: the steepest rise of the insertion force, max dF_ax/d(depth) (N/mm), and
  its ratio to k = 3EI/L^3: how fast the force runs away. Not a jam criterion: measured on the
  study's spring, sliding within 10 % of the reduced model's bound rises at up to 60 k, the stuck
  (jammed) apex at 103-151 k, too close for a robust threshold;
- max_von_mises, yield_ratio (its ratio to the spring's yield stress), yielded: the FE field's
  largest value, which includes the stress concentration at the sharp apex under contact;
- root_stress: the beam stress at the root of spring B, 6 |M| / h^2 + |N| / h (MPa) from the
  support's reactions (M about the root's centre), and root_yield_ratio, its ratio to yield;
- the reduced model's peak insertion force and jam prediction beside them.
"""
import math
import time

import numpy as np

from femcontact.references import snap_fit as reference
from femcontact.config.scene import friction_coefficient
from femcontact.families.repository import SCENES

RATIO_FLOOR = 0.1    # lateral force / its peak below which a ratio is not averaged (first touch, last contact)
STICK_MARGIN = 0.02  # |F_t| < (1 - margin) mu F_n: inside the friction cone, not on its edge (sliding)
NOSE_MARGIN = 0.02   # contact counts as on the nose below z = (1 - margin) H
SCENE = SCENES / "snap_fit_2d.toml"


def _zones(scene: dict) -> list[str]:
    return ["B", "A"][: scene["spring"]["count"]]


def per_width(scene: dict) -> float:
    """Factor from history forces to N: the spring's width in 2-D (per mm), 1 in 3-D."""
    return scene["spring"]["width"] if scene["dim"] == 2 else 1.0


def forces(scene: dict, rows: list[dict]) -> dict:
    """Per row: depth (mm), F_ax, F_lat (N), the contact point's z on the nose (mm) and the
    force of spring B split along the nose's normal and tangent there (N)."""
    from geometry.snap_fit import layout, nose_profile

    width, nose, place = per_width(scene), nose_profile(scene["peg"]), layout(scene)
    out = {key: [] for key in ("depth", "axial", "lateral", "z", "normal", "tangential")}
    for row in rows:
        out["depth"].append(-row["rigid_y"] - scene["peg"]["start_gap"])
        out["axial"].append(-width * sum(row[f"contact_{zone}_Fy"] for zone in _zones(scene)))
        out["lateral"].append(width * sum(abs(row[f"contact_{zone}_Fx"]) for zone in _zones(scene)))
        centre = row["contact_B_y"]  # None (NaN in memory) without contact
        z = (math.nan if centre is None else centre) - place.tip_y - row["rigid_y"]
        out["z"].append(z)
        alpha = float(nose.slope_angle(min(max(z, 0.0), nose.length))) if np.isfinite(z) else 0.0
        force = width * np.array([row["contact_B_Fx"], row["contact_B_Fy"]])  # on spring B
        out["normal"].append(float(force @ [math.cos(alpha), -math.sin(alpha)]))
        out["tangential"].append(float(force @ [math.sin(alpha), math.cos(alpha)]))
    return {key: np.array(value, float) for key, value in out.items()}


def _ratio(f: dict, H: float) -> float:
    on_nose = np.nan_to_num(f["z"], nan=np.inf) < (1 - NOSE_MARGIN) * H
    loaded = f["lateral"] > RATIO_FLOOR * f["lateral"].max(initial=0.0)
    chosen = on_nose & loaded & (f["lateral"] > 0)
    return float(np.mean(f["axial"][chosen] / f["lateral"][chosen])) if chosen.any() else math.nan


def snap_fit_metrics(simulation) -> dict:
    from geometry.snap_fit import nose_profile

    scene, history = simulation.scene, simulation.history
    spring, mu = scene["spring"], friction_coefficient(scene)
    nose = nose_profile(scene["peg"])
    insert = forces(scene, [row for row in history if row["step"] == "insert"])
    withdraw = forces(scene, [row for row in history if row["step"] == "withdraw"])
    out = {"insertion_depth": insert["depth"].tolist(), "insertion_force": insert["axial"].tolist(),
           "lateral_force": insert["lateral"].tolist(), "withdrawal_depth": withdraw["depth"].tolist(),
           "withdrawal_force": (-withdraw["axial"]).tolist(), "withdrawal_lateral_force": withdraw["lateral"].tolist()}
    out["final_contact_force"] = float(insert["lateral"][-1] / spring["count"]) if len(insert["lateral"]) else 0.0
    out["peak_insertion_force"] = float(insert["axial"].max(initial=0.0))
    out["peak_withdrawal_force"] = float((-withdraw["axial"]).max(initial=0.0))
    out["insertion_force_ratio"] = _ratio(insert, nose.length)
    out["withdrawal_force_ratio"] = _ratio(withdraw, nose.length)
    out.update(jamming(scene, [row for row in history if row["step"] == "insert"], insert, mu))
    out["stopped"] = simulation.stopped
    out["max_von_mises"] = max(row["max_von_mises"] for row in history)
    out["yield_ratio"] = out["max_von_mises"] / scene["materials"]["spring"]["yield_stress"]
    out["yielded"] = bool(out["yield_ratio"] > 1)
    out["root_stress"] = root_stress(scene, history)
    out["root_yield_ratio"] = out["root_stress"] / scene["materials"]["spring"]["yield_stress"]
    out.update(reduced_model(scene))
    if nose.kind == "taper":
        alpha = math.radians(scene["peg"]["nose_angle"])
        out["insertion_ratio_statics"] = float(reference.force_ratio(alpha, mu))
        out["withdrawal_ratio_statics"] = float(reference.force_ratio(alpha, mu, withdrawal=True))
    out["wall_time_s"] = float(sum(simulation.timings.values()))
    return out


def jamming(scene: dict, rows: list[dict], insert: dict, mu: float) -> dict:
    """jammed, jam_reason, jam_depth (mm), stuck_increments, buckling_ratio, max_insertion_slope
    (N/mm) of the insertion rows (`insert`: their `forces`)."""
    from geometry.snap_fit import nose_profile

    spring, E = scene["spring"], scene["materials"]["spring"]["E"]
    H = nose_profile(scene["peg"]).length
    touching = (insert["normal"] > RATIO_FLOOR * max(insert["normal"].max(initial=0.0), 1e-300)) \
        & (np.nan_to_num(insert["z"], nan=np.inf) < (1 - NOSE_MARGIN) * H)
    stuck = touching & (np.abs(insert["tangential"]) < (1 - STICK_MARGIN) * mu * insert["normal"])
    k = reference.cantilever_stiffness(E, spring["thickness"], spring["length"], spring["width"])
    step = np.diff(insert["depth"], prepend=0.0)
    slope = np.divide(np.diff(insert["axial"], prepend=0.0), step, out=np.zeros_like(step), where=step > 0)
    euler = math.pi ** 2 * E * spring["width"] * spring["thickness"] ** 3 / 12 / (4 * spring["length"] ** 2)
    axial = np.array([per_width(scene) * abs(row["reaction_root_B_y"]) for row in rows])
    buckled = axial > euler
    reasons, first = [], []
    if stuck.any():
        i = int(np.argmax(stuck))
        reasons.append(f"the contact force lies inside the friction cone at depth {insert['depth'][i]:.4g} mm "
                       f"(|F_t| / F_n = {abs(insert['tangential'][i]) / insert['normal'][i]:.3f} < mu = {mu:g}): "
                       "the apex sticks to the nose")
        first.append(insert["depth"][i])
    if buckled.any():
        i = int(np.argmax(buckled))
        reasons.append(f"the spring buckles at depth {insert['depth'][i]:.4g} mm (axial root force {axial[i]:.4g} N "
                       f"> Euler load pi^2 EI / 4L^2 = {euler:.4g} N)")
        first.append(insert["depth"][i])
    return {"jammed": bool(reasons), "jam_reason": "; ".join(reasons) or None,
            "jam_depth": float(min(first)) if first else None, "stuck_increments": int(stuck.sum()),
            "buckling_ratio": float(axial.max(initial=0.0) / euler),
            "max_insertion_slope": float(slope.max(initial=0.0)), "max_insertion_slope_over_k": float(slope.max(initial=0.0) / k)}


def root_stress(scene: dict, rows: list[dict]) -> float:
    """Largest beam stress (MPa) at the root of spring B over the rows: bending 6 |M| / h^2 plus
    axial |N| / h, from the root's reactions per mm of width (the moment recorded about the origin
    is moved to the root's centre; 3-D reactions are divided by the width)."""
    from geometry.snap_fit import layout

    h = scene["spring"]["thickness"]
    scale = per_width(scene) / scene["spring"]["width"]  # history reactions to N/mm of width
    centre = layout(scene).inner + h / 2
    return float(max((scale * (6 * abs(row["reaction_root_B_Mz"] - centre * row["reaction_root_B_y"]) / h ** 2
                               + abs(row["reaction_root_B_y"]) / h) for row in rows), default=0.0))


def reduced_model(scene: dict) -> dict:
    """The rigid-arm model's predictions for the scene: stiffness, final force, peak insertion
    force and jamming (femcontact.references.snap_fit)."""
    from geometry.snap_fit import layout, nose_profile

    spring, material = scene["spring"], scene["materials"]["spring"]
    mu = friction_coefficient(scene)
    nose, place = nose_profile(scene["peg"]), layout(scene)
    k = reference.cantilever_stiffness(material["E"], spring["thickness"], spring["length"], spring["width"])
    couple = reference.coupling(spring)
    depth = np.linspace(0.0, 1.1 * (nose.length - place.contact_depth), 400)  # the nose and onto the shank
    lateral, axial = reference.rigid_arm_forces(nose, place.apex[0], k, mu, couple, depth)
    z = place.contact_depth + depth
    alpha = nose.slope_angle(np.minimum(z, nose.length * (1 - 1e-9)))
    return {"stiffness_3EI_L3": k, "model_final_contact_force": float(lateral[-1]),
            "model_peak_insertion_force": float(np.nanmax(axial)) * spring["count"] if np.isfinite(axial).any()
            else math.inf,
            "model_jammed": bool(reference.jams(alpha, mu, couple).any()),
            "cone_jammed": bool(reference.jams_by_friction_cone(alpha, mu).any()),
            "max_nose_angle_deg": float(np.degrees(alpha.max()))}


def accuracy_case(knob: str, setting: str, overrides: list[str]) -> dict:
    """One run of scenes/snap_fit_2d.toml for `make accuracy`: wall time (s) of mesh, forms, solve
    and metrics, the peak insertion force (N) and the insertion force ratio against the statics."""
    from femcontact.families import load_scene
    from femcontact.solver.stepping import Simulation

    start = time.perf_counter()
    scene = load_scene(SCENE, overrides)
    simulation = Simulation(scene)
    simulation.run()
    m = snap_fit_metrics(simulation)
    return {"knob": knob, "setting": setting, "dofs": simulation.dofs, "wall_time": time.perf_counter() - start,
            "newton_iterations": sum(row["newton_iterations"] for row in simulation.history),
            "resolution": scene["mesh"]["resolution"], "increments": scene["steps"][0]["increments"],
            "peak_insertion_force": m["peak_insertion_force"], "insertion_force_ratio": m["insertion_force_ratio"],
            "insertion_ratio_statics": m["insertion_ratio_statics"],
            "error_insertion_force_ratio": abs(m["insertion_force_ratio"] / m["insertion_ratio_statics"] - 1)}


def accuracy_rows() -> tuple[list[dict], list[str]]:
    """`make accuracy` rows of the contract scene (two springs, taper 30 deg, mu 0.2): mesh
    resolution at the scene's 40 increments per step, and increments per step at resolution 1.
    Errors: the insertion force ratio against the statics tan(alpha + phi); the peak insertion
    force against a Richardson extrapolation of each knob's three finest settings (or the finest)."""
    from femcontact.references.richardson import richardson

    accuracy_case("", "warm-up", ["mesh.resolution=0.5"])
    resolutions, increments = (0.5, 0.7, 1.0, 1.4, 2.0), (10, 20, 40, 80, 160, 320)
    mesh = [accuracy_case("mesh (P2)", f"resolution {r:g}", [f"mesh.resolution={r}"]) for r in resolutions]
    steps = [accuracy_case("increments", f"{n} per step", [f"steps.0.increments={n}", f"steps.1.increments={n}"])
             for n in increments]
    notes = [f"Insertion force ratio against the statics tan(alpha + phi) = {mesh[0]['insertion_ratio_statics']:.6f} "
             "(taper 30 deg, mu 0.2)."]
    for rows, label, ratio, what in ((mesh, "resolutions", resolutions[-1] / resolutions[-2], "resolution"),
                                     (steps, "increment counts", 2.0, "increments")):
        finest = [row["peak_insertion_force"] for row in rows[-3:]]
        limit, order = richardson(finest, ratio)
        for row in rows:
            row["error_peak_insertion_force"] = abs(row["peak_insertion_force"] / limit - 1)
        settings = ", ".join(row["setting"] for row in rows[-3:])
        how = (f"Richardson extrapolation of {settings} (observed order {order:.2f})"
               if math.isfinite(order) and order > 0 else
               f"the finest setting, {rows[-1]['setting']} (no Richardson: the three finest values do not converge "
               f"monotonically, observed order {order:.2f})")
        notes.append(f"Reference peak insertion force for the {label}: {limit:.6g} N, from {how}.")
    return mesh + steps, notes
