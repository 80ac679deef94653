"""Wedge metrics of a peg-in-hole run (the thesis, ch. 3): is the peg held after release?

After the last step (the load removed) the residual reactions on the two hole blocks
are read at their supports (2-D two blocks; a single block uses the contact resultants
of its zones A and B). The peg is *wedged* when all of these hold:

1. **held**: |R_A| > `FORCE_FLOOR` x the load scale, the load scale being the peak
   applied force, or for a moment-only load the peak moment over the distance between
   the contact points l_2P (the force of the equivalent couple). Measured (docs/wedging.md):
   wedged pegs keep 1.0-2.7x the peak load (5-13 N for a 5.1 N push); a free peg ends at
   0 or, when the solver had to keep a stabilised state, at < 0.7 % of it (0.03 N of
   5.1 N at l_d = 10). 2 % separates the two by a factor > 3 on both sides.
2. **in equilibrium without help**: the released state needed no contact stabilisation,
   i.e. `stabilization_force_released` (the largest stabilisation force of the increments
   after the load is gone) <= `STABILIZATION_TOL` x |R_A|. A free peg has no exact
   quasi-static equilibrium (it would move), so the solver keeps a stabilised state and
   reports a non-zero stabilisation force: that state is not a wedge whatever its forces.
3. **balanced**: imbalance = |R_A + R_B| / |R_A| < `IMBALANCE_TOL` (1e-3, the thesis'
   criterion; the converged solver gives ~1e-15: reactions come from the assembled
   residual, so they balance the zero external load to solver tolerance). For a peg that is
   not held the imbalance and the angles below are None: ratios of reactions at round-off
   (1e-11 to 1e-7 N measured on 3-D pegs of the stability sweep), which change between two
   runs on 2 ranks.
4. **collinear**: each reaction makes at most `ANGLE_TOL_DEG` with the line joining the
   two contact points (the contact-force centres of zones A and B). A wedged peg is a
   two-force body, so its reactions must lie on that line; measured deviations are
   < 1e-3 deg, and 1 deg allows for the discretised contact-point position (the contact
   centres move by a fraction of an element, 0.08 mm at resolution 1, over l_2P ~ 40 mm).

`tilt_change_deg` = loaded - initial tilt. For the thesis' published cases (d 40, D 40.1, mu 0.2,
push (-5, 1) N, l_d = 4, 5, 6: `THESIS_CASES`) the thesis' values sit beside ours
(`thesis_tilt_change_deg`, `thesis_residual_force_A`) with the ratios ours / thesis
(`tilt_change_over_thesis`, `residual_over_thesis`), so a study of set-ups can be ranked.
`push_friction_needed` is the least mu with which a rigid peg at the placement holds the first
step's load (`references.two_point_statics`): below the scene's mu the push alone cannot
make a rigid peg slide.

`wedge_reason` says which condition failed ("wedged" when none). The analytic condition
l_crit <= l_d <= mu d (geometric, `femcontact.analytic`) is reported beside it
(`analytic_wedged`, normalised depths `depth_over_l_crit`, `depth_over_l_max`, and
`boundary_distance` = the distance of l_d from the nearer bound over l_max), so a study
can tabulate the agreement. `wall_time_s` is the solver's own time (mesh, forms, solve,
output) of the case; the runner's `time.total` adds Python start-up and scene loading.
"""
import math

import numpy as np

from femcontact.references import peg_in_hole as analytic
from femcontact.references.two_point_statics import step_friction_needed
from femcontact.config.scene import friction_coefficient

FORCE_FLOOR = 0.02        # residual force / load scale below which the peg is free
STABILIZATION_TOL = 1e-3  # stabilisation force after release / residual force
IMBALANCE_TOL = 1e-3      # |R_A + R_B| / |R_A|
ANGLE_TOL_DEG = 1.0       # deviation of a reaction from the line of the contact points
BOUNDARY_BAND = 0.05      # |l_d - bound| / l_max below which a case counts as "near a boundary"

THESIS_CASES = {  # l_d (mm): tilt initial, loaded, released (deg), R_A (x, y) (N); thesis Table 3-3
    4.0: (1.6784, 3.6418, 3.6224, 13.256854, -0.434447),
    5.0: (1.2560, 2.0619, 2.0402, 11.723917, -0.987158),
    6.0: (1.0148, 1.4898, 1.4629, 9.400392, -1.106843),
}


def thesis_metrics(scene: dict, out: dict) -> dict:
    """The thesis' tilt change and residual reaction beside ours, for a scene of its wedging
    cases (d 40, D 40.1, mu 0.2, first step the push (-5, 1) N); {} for any other scene."""
    published = THESIS_CASES.get(scene["peg"]["insertion_depth"])
    push = scene["steps"][0]["force"]
    if not published or (scene["peg"]["width"], scene["hole"]["width"], scene["contact"]["mu"]) != (40.0, 40.1, 0.2) \
            or list(push) != [-5.0, 1.0] or scene["steps"][0]["moment"]:
        return {}
    change, residual = published[1] - published[0], float(np.hypot(published[3], published[4]))
    return {"thesis_tilt_change_deg": change, "thesis_residual_force_A": residual,
            "tilt_change_over_thesis": out["tilt_change_deg"] / change,
            "residual_over_thesis": out["residual_force_A"] / residual}


def _vector(row: dict, prefix: str, dim: int) -> np.ndarray:
    """A vector of a history row; nan for components the row leaves empty (None)."""
    values = [row.get(f"{prefix}_{axis}") for axis in "xyz"[:dim]]
    return np.array([np.nan if value is None else value for value in values], dtype=float)


def _loaded(row: dict, dim: int) -> bool:
    return any(abs(row.get(f"applied_F{a}", 0.0)) > 0 for a in "xyz"[:dim])


def analytic_metrics(scene: dict) -> dict:
    """The geometric wedging condition of the scene (2-D formulas, also used in 3-D in the x-z plane)."""
    d, D, l_d = scene["peg"]["width"], scene["hole"]["width"], scene["peg"]["insertion_depth"]
    mu = friction_coefficient(scene)
    crit, top = analytic.l_crit(d, D), analytic.l_max(d, mu)
    out = {"clearance_ratio": analytic.clearance_ratio(d, D), "l_crit": crit, "l_max": top,
           "depth_over_l_crit": l_d / crit, "depth_over_l_max": l_d / top if top > 0 else math.inf,
           "analytic_wedged": bool(crit <= l_d <= top)}
    out["boundary_distance"] = min(abs(l_d - crit), abs(l_d - top)) / top if top > 0 else math.inf
    out["near_boundary"] = bool(out["boundary_distance"] < BOUNDARY_BAND)
    return out


def no_equilibrium_metrics(scene: dict) -> dict:
    """The wedging answer of a run whose load has no static equilibrium: not wedged, and the
    analytic bounds of its scene."""
    return {"wedged": False, "wedge_reason": "no static equilibrium under load", **analytic_metrics(scene)}


def push_friction_needed(scene: dict) -> float | None:
    """The least mu with which a rigid peg at the two-point placement holds the first step's load
    (`references.two_point_statics`); None for a load point the placement does not name (the
    peg's reference point) or a scene without a two-point placement."""
    return step_friction_needed(scene, scene["steps"][0])


def load_scale(scene: dict, history: list[dict]) -> float:
    """Peak applied force (N), or for moments the force of the couple over l_2P, whichever is larger."""
    dim = scene["dim"]
    force = max((np.linalg.norm([row.get(f"applied_F{a}", 0.0) for a in "xyz"[:dim]]) for row in history),
                default=0.0)
    moment = max((np.linalg.norm(step["moment"]) for step in scene["steps"] if step["moment"]), default=0.0)
    arm = analytic.l_2p(scene["peg"]["width"], scene["peg"]["insertion_depth"])
    return float(max(force, moment / arm))


def wedge_metrics(simulation) -> dict:
    scene, dim = simulation.scene, simulation.scene["dim"]
    history = simulation.history
    final = history[-1]
    out = {"tilt_initial_deg": float(np.degrees(simulation.problem.model.rigid["tilt"])),
           "tilt_released_deg": final["tilt_deg"]}
    last_loaded = max((i for i, row in enumerate(history) if _loaded(row, dim)), default=-1)
    if any(step["moment"] for step in scene["steps"]):  # moments are not in the rows: all but the last step
        last_loaded = max((i for i, row in enumerate(history) if row["step"] != final["step"]), default=-1)
    loaded = [row["tilt_deg"] for row in history[: last_loaded + 1]]
    out["tilt_loaded_deg"] = max(loaded, key=abs) if loaded else final["tilt_deg"]
    out["tilt_change_deg"] = out["tilt_loaded_deg"] - out["tilt_initial_deg"]
    released = history[last_loaded + 1:] or [final]
    out["stabilization_force_released"] = float(max(row.get("stabilization_force", 0.0) for row in released))
    forces = {}
    for zone in ("A", "B"):
        supports = [name for name in simulation.problem.support_dofs if name.endswith(zone)]
        vector = sum((_vector(final, f"reaction_{name}", dim) for name in supports), np.zeros(dim))
        if not supports:  # single block: use the contact resultants of the zone
            vector = -np.array([final.get(f"contact_{zone}_F{axis}", np.nan) for axis in "xyz"[:dim]])
        forces[zone] = vector
        out[f"residual_force_{zone}"] = float(np.linalg.norm(vector))
        for k, axis in enumerate("xyz"[:dim]):
            out[f"residual_force_{zone}_{axis}"] = float(vector[k])
    R_A, R_B = forces["A"], forces["B"]
    scale = load_scale(scene, history)
    out["load_scale"] = scale
    out["residual_over_load"] = out["residual_force_A"] / scale if scale > 0 else math.inf
    held = out["residual_force_A"] > FORCE_FLOOR * scale
    point_A = _vector(final, "contact_A", dim)
    point_B = _vector(final, "contact_B", dim)
    line = point_B - point_A
    # undefined (JSON null) for a free peg, whose reactions are round-off; the angles also where a
    # zone has lost contact (no line of the contact points)
    out["imbalance"] = float(np.linalg.norm(R_A + R_B) / max(np.linalg.norm(R_A), 1e-300)) if held else None
    angles, angle_reason = [None, None], None
    if not held:
        angle_reason = "no residual force after release: the reactions' balance and angles are undefined"
    elif not np.all(np.isfinite(line)):
        angle_reason = "zone " + " and ".join(z for z, p in (("A", point_A), ("B", point_B))
                                              if not np.all(np.isfinite(p))) \
            + " has no contact after release: the angles to the line of the contact points are undefined"
    else:
        angles = [float(np.degrees(np.arccos(np.clip(abs(vector @ line) / max(
            np.linalg.norm(vector) * np.linalg.norm(line), 1e-300), -1, 1)))) for vector in (R_A, R_B)]
    out["angle_A_deg"], out["angle_B_deg"] = angles
    out["angle_reason"] = angle_reason
    out["elastic_energy"] = final["elastic_energy"]
    out["max_von_mises"] = max(row["max_von_mises"] for row in history)
    out["yield_ratio"] = out["max_von_mises"] / scene["materials"][simulation.problem.deformable]["yield_stress"]
    if not held:
        reason = "no residual force"
    elif out["stabilization_force_released"] > STABILIZATION_TOL * out["residual_force_A"]:
        reason = "no equilibrium after release (stabilised state)"
    elif not out["imbalance"] < IMBALANCE_TOL:
        reason = "unbalanced"
    elif angles[0] is None or not max(angles) <= ANGLE_TOL_DEG:
        reason = "not collinear"
    else:
        reason = "wedged"
    out["wedge_reason"] = reason
    out["wedged"] = reason == "wedged"
    out.update(analytic_metrics(scene))
    out.update(thesis_metrics(scene, out))
    out["push_friction_needed"] = push_friction_needed(scene)
    out["wall_time_s"] = float(sum(simulation.timings.values()))
    return out
