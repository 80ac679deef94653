"""Nose design with the reduced (rigid-arm) model: the profile's points are optimised, the
winner is then checked by FE in `studies/snap_fit.toml`.

The nose's working part (the stroke s over which the spring's apex rides on it, from first
touch at r_apex = w - interference to the shank at r = w) is cut into `segments` of equal axial
length s/n with angles alpha_j (rad, from the axis); their rises add up to the interference.
Below r_apex the nose is never touched: a straight run to the tip at the first segment's angle.
Two designs at the stroke of a flat taper:

- `constant` (Whitney's constant-force nose, here in closed form): the reduced model's insertion
  force is F_ax = k delta t / (1 - c t), t = tan(alpha + phi), c = 1.5 e/L, so it stays at F where
  alpha(delta) = atan(F / (k delta + c F)) - phi; dz = d delta / tan(alpha) gives the profile, and
  F is found (brentq) so that the working part has the taper's axial length;
- `min_peak`: the segment angles optimised by SLSQP (scipy) from the constant-force nose, minimising the
  largest insertion force over the stroke (epigraph form: minimise F with F_ax(d) <= F at the
  sample depths).

Angles are capped at `MAX_ANGLE_DEG` so the nose stays clear of the model's jam condition.
`python -m femcontact.families.snap_fit.design [scene.toml]` prints both designs as
`peg.nose_points` lines for a study file, with their predicted peak forces.
"""
import math
import sys

import numpy as np

from femcontact.references import snap_fit as reference
from femcontact.config.scene import friction_coefficient

MAX_ANGLE_DEG = 60.0


def _model(scene: dict):
    spring, material = scene["spring"], scene["materials"]["spring"]
    mu = friction_coefficient(scene)
    k = reference.cantilever_stiffness(material["E"], spring["thickness"], spring["length"], spring["width"])
    return k, mu, reference.coupling(spring)


def points_for(scene: dict, angles: np.ndarray, stroke: float) -> list[list[float]]:
    """nose_points [[r, z]] (mm) of a nose whose working part has the given segment angles (rad)."""
    w, i = scene["peg"]["width"] / 2, scene["spring"]["interference"]
    r_apex = w - i
    dz = stroke / len(angles)
    lead = min(r_apex, 0.2 * w)  # the untouched run below the apex radius, at the first angle
    z0 = lead / math.tan(angles[0])
    points = [[r_apex - lead, 0.0], [r_apex, z0]]
    for alpha in angles:
        r, z = points[-1]
        points.append([r + dz * math.tan(alpha), z + dz])
    points[-1][0] = w  # the rises add up to the interference (to round-off)
    return points


def forces(scene: dict, points, samples: int = 200) -> tuple[np.ndarray, np.ndarray]:
    """(depth, F_ax) of the reduced model for a points nose, over its working stroke and a little beyond."""
    from geometry.snap_fit import nose_profile

    peg = {**scene["peg"], "nose": "points", "nose_points": points}
    nose = nose_profile(peg)
    k, mu, couple = _model(scene)
    r_apex = nose.half_width - scene["spring"]["interference"]
    stroke = nose.length - nose.depth_at(r_apex)
    depth = np.linspace(0.0, stroke, samples)
    _, axial = reference.rigid_arm_forces(nose, r_apex, k, mu, couple, depth)
    return depth, axial * scene["spring"]["count"]


def constant_force(scene: dict, stroke: float, points: int = 24) -> dict:
    """Whitney's constant-force nose for the reduced model, its working part `stroke` (mm) long."""
    from scipy.integrate import quad
    from scipy.optimize import brentq

    k, mu, couple = _model(scene)
    w, i = scene["peg"]["width"] / 2, scene["spring"]["interference"]
    cap, phi = math.radians(MAX_ANGLE_DEG), math.atan(mu)

    def angle(delta, F):
        return max(min(math.atan(F / (k * delta + couple * F)) - phi, cap), math.radians(1.0))

    def length(F, top=i):
        return quad(lambda d: 1 / math.tan(angle(d, F)), 0.0, top, limit=200)[0]

    F = brentq(lambda F: length(F) - stroke, 1e-6 * k * i, 100 * k * i, xtol=1e-12 * k * i)
    deltas = i * (np.linspace(0.0, 1.0, points) ** 1.5)  # denser where the angle turns fastest
    r_apex, lead = w - i, min(w - i, 0.2 * w)
    z0 = lead / math.tan(angle(0.0, F))
    profile = [[r_apex - lead, 0.0]] + [[r_apex + d, z0 + length(F, d)] for d in deltas]
    profile[-1][0] = w
    depth, force = forces(scene, profile)
    return {"objective": "constant", "points": profile, "force": F, "peak": float(np.nanmax(force)),
            "converged": True, "angles_deg": []}


def design(scene: dict, objective: str, stroke: float, segments: int = 12) -> dict:
    """The `constant` nose (closed form) or the `min_peak` nose (optimised segment angles) at the
    given stroke (mm)."""
    if objective == "constant":
        return constant_force(scene, stroke)
    from scipy.optimize import minimize

    i = scene["spring"]["interference"]
    dz = stroke / segments
    cap = math.radians(MAX_ANGLE_DEG)
    r, z = np.array(constant_force(scene, stroke)["points"][1:]).T  # start from the constant-force nose
    rises = np.diff(np.interp(z[0] + dz * np.arange(segments + 1), z, r))
    start = np.clip(np.arctan(rises / dz), math.radians(1.0), cap)

    def profile(x):
        return forces(scene, points_for(scene, x[:segments], stroke), samples=120)[1]

    rise = {"type": "eq", "fun": lambda x: np.sum(np.tan(x[:segments])) * dz - i}
    bounds = [(math.radians(1.0), cap)] * segments
    peak0 = float(np.nanmax(profile(start)))
    x0 = np.r_[start, 1.0]  # the last variable: the peak over the starting nose's peak
    below = {"type": "ineq", "fun": lambda x: x[-1] - profile(x) / peak0}
    result = minimize(lambda x: x[-1], x0, method="SLSQP", bounds=bounds + [(0.0, 2.0)],
                      constraints=[rise, below], options={"maxiter": 300, "ftol": 1e-12})
    angles = result.x[:segments]
    points = points_for(scene, angles, stroke)
    depth, force = forces(scene, points)
    return {"objective": objective, "points": points, "angles_deg": np.degrees(angles).tolist(),
            "peak": float(np.nanmax(force)), "converged": bool(result.success)}


def taper_stroke(scene: dict) -> float:
    """Working stroke (mm) of the scene's flat taper: interference / tan(angle)."""
    return scene["spring"]["interference"] / math.tan(math.radians(scene["peg"]["nose_angle"]))


def main(argv=None) -> int:
    from femcontact.families import load_scene
    from femcontact.families.snap_fit.metrics import reduced_model

    argv = sys.argv[1:] if argv is None else argv
    scene = load_scene(argv[0] if argv else "scenes/snap_fit_2d.toml", argv[1:])
    stroke = taper_stroke(scene)
    taper = reduced_model(scene)["model_peak_insertion_force"]
    print(f"# flat taper {scene['peg']['nose_angle']:g} deg, stroke {stroke:.4g} mm: model peak {taper:.4g} N")
    for objective in ("constant", "min_peak"):
        result = design(scene, objective, stroke)
        text = ", ".join(f"[{r:.6f}, {z:.6f}]" for r, z in result["points"])
        print(f"# {objective}: model peak {result['peak']:.4g} N ({100 * (1 - result['peak'] / taper):.1f} % below "
              f"the taper), segment angles {', '.join(f'{a:.1f}' for a in result['angles_deg'])} deg, "
              f"converged {result['converged']}")
        print(f'{{ "peg.nose" = "points", "peg.nose_points" = [{text}] }},')
    return 0


if __name__ == "__main__":
    sys.exit(main())
