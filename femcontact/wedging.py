"""Wedge metrics of a peg-in-hole run (reference §1): is the peg held after release?

After the last step the residual reactions on the two hole blocks are read. A peg is
*wedged* when the residual contact forces are non-zero (above `FORCE_FLOOR` of the
applied load), balanced (|R_A + R_B| / |R_A| below `IMBALANCE_TOL`) and collinear
with the line joining the two contact points (within `ANGLE_TOL_DEG` of it, or of
its friction cone).
"""
import numpy as np

FORCE_FLOOR = 1e-3      # residual force / peak applied force below which the peg is free
IMBALANCE_TOL = 1e-3    # |R_A + R_B| / |R_A|
ANGLE_TOL_DEG = 1.0     # deviation of a reaction from the line of the contact points beyond the friction cone


def _vector(row: dict, prefix: str, dim: int) -> np.ndarray:
    return np.array([row.get(f"{prefix}_{axis}", np.nan) for axis in "xyz"[:dim]])


def wedge_metrics(simulation) -> dict:
    scene, dim = simulation.scene, simulation.scene["dim"]
    history = simulation.history
    first_rows = {}
    for row in history:
        first_rows.setdefault(row["step"], row)
    ends = simulation.step_end_rows()
    final = history[-1]
    peak_load = max(np.linalg.norm([row.get(f"applied_F{a}", 0.0) for a in "xyz"[:dim]]) for row in history)
    mu = scene["contact"]["mu"] if "friction" in scene["effects"] else 0.0
    out = {"tilt_initial_deg": float(np.degrees(simulation.problem.model.rigid["tilt"])),
           "tilt_released_deg": final["tilt_deg"]}
    loaded = [row["tilt_deg"] for row in history if any(abs(row.get(f"applied_F{a}", 0.0)) > 0 for a in "xyz"[:dim])]
    out["tilt_loaded_deg"] = max(loaded, key=abs) if loaded else final["tilt_deg"]
    forces = {}
    for zone in ("A", "B"):
        supports = [name for name in simulation.problem.support_dofs if name.endswith(zone)]
        vector = sum((_vector(final, f"reaction_{name}", dim) for name in supports), np.zeros(dim))
        if not supports:  # single block: use the contact resultants of the zone
            vector = -_vector(final, f"contact_{zone}_F", dim)
        forces[zone] = vector
        out[f"residual_force_{zone}"] = float(np.linalg.norm(vector))
        for k, axis in enumerate("xyz"[:dim]):
            out[f"residual_force_{zone}_{axis}"] = float(vector[k])
    R_A, R_B = forces["A"], forces["B"]
    out["imbalance"] = float(np.linalg.norm(R_A + R_B) / max(np.linalg.norm(R_A), 1e-300))
    point_A = _vector(final, "contact_A", dim)
    point_B = _vector(final, "contact_B", dim)
    line = point_B - point_A
    angles = []
    for vector in (R_A, R_B):
        cosine = abs(vector @ line) / max(np.linalg.norm(vector) * np.linalg.norm(line), 1e-300)
        angles.append(float(np.degrees(np.arccos(np.clip(cosine, -1, 1)))) if np.all(np.isfinite(line)) else np.nan)
    out["angle_A_deg"], out["angle_B_deg"] = angles
    out["elastic_energy"] = final["elastic_energy"]
    out["max_von_mises"] = max(row["max_von_mises"] for row in history)
    cone = np.degrees(np.arctan(mu)) + ANGLE_TOL_DEG
    held = out["residual_force_A"] > FORCE_FLOOR * max(peak_load, 1e-300)
    out["wedged"] = bool(held and out["imbalance"] < IMBALANCE_TOL and max(angles) <= cone)
    return out
