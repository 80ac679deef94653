"""`make convergence_3d`: the 3-D headline answers under mesh refinement, with their
discretisation error.

Each ladder in LADDERS runs one scene as a whole `mpirun -n 2 femcontact run` process at mesh
resolutions each sqrt(2) finer than the last (element sizes / sqrt(2), about 2.8x the unknowns):
scenes/wedging_3d.toml (a rigid peg wedged in a stainless block by a 1000 N mm couple, then
released), scenes/insertion_3d.toml (a tilted peg with a rounded rim on compliant springs, into
two-point contact), both also with the contact on the hole's exact surface (`contact.surface =
"exact"`), the wedging also with quadratic elements on the exact surface (`mesh.degree = 2`,
resolutions 0.5 to 1.41), both on curved quadratic elements (`mesh.geometry_order = 2`, the same
rungs), there and on the wedging's linear elements also with the contact force along the wall's
normal (`contact.normal = "wall"`, which both scenes name; their other ladders set the peg's
normal, "body"), the chamfer crossing of the tilted peg on the RCC (the second case of
studies/insertion_3d.toml) on curved quadratic elements along the wall's normal, and
scenes/snap_fit_3d.toml (a pin pushed past a cantilever spring and withdrawn). For each
answer in a ladder's quantities: the value on every rung, the Richardson extrapolation of the
three finest (`femcontact.references.richardson`) with its observed order, the estimated error of
the finest rung, |finest - extrapolated| / |extrapolated| (at an observed order above the
discretisation's, that order with a factor of safety 3: `finest_error`; where the rungs do not
converge monotonically, 3 x the spread: `range_error`), and the spread of the three finest rungs
(largest - smallest) / finest. A rung whose result.json exists is read, not run
again (delete results/convergence_3d/LADDER/r<resolution> to re-run it). Writes
results/convergence_3d/convergence_3d.md and .json after every rung.

    python -m benchmarks.convergence_3d [--ladder wedging_3d ...] [--resolutions 1 1.4142 2 2.8284] [--ranks 2]
"""
import argparse
import json
import math
import sys
from dataclasses import dataclass, field, replace
from pathlib import Path

from femcontact.errors import InputError
from femcontact.families.repository import SCENES
from femcontact.io import read_result, write_json_atomic, write_text_atomic
from femcontact.outputs.tables import markdown_table
from femcontact.references.richardson import RANGE_FACTOR, SAFETY_FACTOR, finest_error, range_error, richardson, spread

from benchmarks.whole_process import run_scene

OUT = Path("results/convergence_3d")
RESOLUTIONS = (1.0, 2 ** 0.5, 2.0, 2 * 2 ** 0.5)
"""Mesh resolutions of a ladder unless it names its own."""
TARGET = 0.01
"""The discretisation error a published 3-D number should carry at most."""


@dataclass(frozen=True)
class Ladder:
    """One scene refined rung by rung, with `settings` (key -> TOML value) on every rung, and the
    result.json metrics reported, with what they are."""
    scene: str
    title: str
    quantities: dict
    resolutions: tuple = RESOLUTIONS
    settings: dict = field(default_factory=dict)
    order_limit: float = 2.0
    """The highest order the discretisation can deliver (P1 contact: 2): where the rungs line up
    at an order above it, the error is estimated at this order with a factor of safety 3."""


EXACT = {"contact.surface": "'exact'"}
"""The contact measured on the hole's exact round surfaces (docs/wedging_3d.md)."""
CURVED = {"mesh.degree": "2", "mesh.geometry_order": "2"}
"""Quadratic elements with curved (quadratic) geometry: the hole's cylinder and cone to within h^3."""
WALL_NORMAL = {"contact.normal": "'wall'"}
"""The contact force along the hole wall's normal where the wall is smooth (the 3-D wedging and
insertion scenes name it)."""
BODY_NORMAL = {"contact.normal": "'body'"}
"""The contact force along the rigid body's normal."""
P2_RESOLUTIONS = (0.5, 0.5 * 2 ** 0.5, 1.0, 2 ** 0.5)
"""Rungs of the quadratic ladders: about the unknowns of the linear ones at twice the resolution."""


WEDGING = Ladder("wedging_3d.toml", "3-D wedging under mesh refinement", {
    "residual_force_A": "contact force at A after release (N)",
    "load.contact_A_force": "contact force at A under the couple (N)",
    "tilt_loaded_deg": "tilt under the couple (deg)",
    "tilt_released_deg": "tilt after release (deg)",
    "tilt_change_deg": "tilt change under the couple (deg)",
    "release.contact_B_z": "height of the contact centre B after release (mm)",
}, resolutions=RESOLUTIONS + (4.0,))  # a fifth rung, 778k unknowns (47 min on 2 ranks)
INSERTION = Ladder("insertion_3d.toml", "3-D insertion under mesh refinement", {
    "peak_force": "largest insertion force in the hole (N)",
    "insert.support_Fz": "insertion force at s = 4.45 mm (N)",
    "insert.support_Fx": "lateral force at s = 4.45 mm (N)",
    "insert.contact_A_force": "contact force at A (the mouth) at s = 4.45 mm (N)",
    "insert.contact_B_force": "contact force at B (the rim) at s = 4.45 mm (N)",
    "insert.tilt_xz_deg": "tilt at s = 4.45 mm (deg)",
})
CROSSING = Ladder("insertion_3d.toml", "3-D chamfer crossing on the RCC under mesh refinement", {
    "chamfer_peak_force": "crossing peak (N)",
    "cone.support_Fz": "insertion force at the end of step cone, rolling over the edge (N)",
    "cone.support_Fx": "lateral force at the end of step cone (N)",
    "edge.support_Fz": "insertion force at the end of step edge, on the wall (N)",
})
RCC_CROSSING = {"support.model": "'rcc'", "support.rcc": "{b=55.0, peg_length=50.0, theta_l=70.0, k=20.0}",
                "support.compliance_centre": "20.0", "peg.offset": "0.6", "peg.tilt": "-1.0",
                "peg.insertion_depth": "0.9", "mesh.contact_zone": "3.0",
                "steps": "[{name='cone', increments=9, support_motion={z=-0.45}}, "
                         "{name='edge', increments=7, support_motion={z=-1.15}}, "
                         "{name='side', increments=4, support_motion={z=-2.35}, "
                         "stop={column='support_Fz', value=100.0}}]"}
"""The second case of studies/insertion_3d.toml: the rounded rim of a peg on the Draper-like RCC,
0.6 mm off the axis and tilted -1 deg, across the chamfer, over its edge and down the wall."""
SNAP_FIT = Ladder("snap_fit_3d.toml", "3-D snap fit under mesh refinement", {
    "peak_insertion_force": "peak insertion force (N)",
    "max_insertion_slope": "insertion force per mm of travel (N/mm)",
    "peak_withdrawal_force": "peak withdrawal force (N)",
    "final_contact_force": "contact force on the spring at full insertion (N)",
    "root_stress": "beam stress at the spring's root (MPa)",
}, order_limit=3.0)
LADDERS = {"wedging_3d": replace(WEDGING, settings=BODY_NORMAL,
                                 title="3-D wedging, the force along the peg's normal, under mesh refinement"),
           "wedging_3d_wall": replace(WEDGING, settings=WALL_NORMAL, resolutions=RESOLUTIONS,
                                      title="3-D wedging, the force along the wall's normal, under mesh refinement"),
           "wedging_3d_exact": replace(WEDGING, settings={**EXACT, **BODY_NORMAL}, resolutions=RESOLUTIONS,
                                       title="3-D wedging on the exact hole surface, the force along the peg's "
                                             "normal, under mesh refinement"),
           "insertion_3d": replace(INSERTION, settings=BODY_NORMAL,
                                   title="3-D insertion, the force along the peg's normal, under mesh refinement"),
           "insertion_3d_exact": replace(INSERTION, settings={**EXACT, **BODY_NORMAL},
                                         title="3-D insertion on the exact hole surface, the force along the peg's "
                                               "normal, under mesh refinement"),
           "wedging_3d_p2_exact": replace(WEDGING, settings={**EXACT, "mesh.degree": "2", **BODY_NORMAL},
                                          resolutions=P2_RESOLUTIONS, order_limit=3.0,
                                          title="3-D wedging at P2 on the exact hole surface, the force along the "
                                                "peg's normal, under mesh refinement"),
           "wedging_3d_p2_curved": replace(WEDGING, settings={**CURVED, **BODY_NORMAL}, resolutions=P2_RESOLUTIONS,
                                           order_limit=3.0,
                                           title="3-D wedging on curved quadratic elements, the force along the "
                                                 "peg's normal, under mesh refinement"),
           "insertion_3d_p2_curved": replace(INSERTION, settings={**CURVED, **BODY_NORMAL}, resolutions=P2_RESOLUTIONS,
                                             order_limit=3.0,
                                             title="3-D insertion on curved quadratic elements, the force along the "
                                                   "peg's normal, under mesh refinement"),
           "wedging_3d_p2_wall": replace(WEDGING, settings={**CURVED, **WALL_NORMAL}, resolutions=P2_RESOLUTIONS,
                                         order_limit=3.0,
                                         title="3-D wedging on curved quadratic elements, the force along the wall's "
                                               "normal, under mesh refinement"),
           "insertion_3d_p2_wall": replace(INSERTION, settings={**CURVED, **WALL_NORMAL}, order_limit=3.0,
                                           resolutions=P2_RESOLUTIONS + (2.0,),  # a fifth rung, 275k unknowns
                                                                                 # (10 min on 2 ranks)
                                           title="3-D insertion on curved quadratic elements, the force along the "
                                                 "wall's normal, under mesh refinement"),
           "insertion_3d_rcc_p2_wall": replace(CROSSING, settings={**RCC_CROSSING, **CURVED, **WALL_NORMAL},
                                               resolutions=P2_RESOLUTIONS + (2.0,), order_limit=3.0,
                                               title="3-D chamfer crossing on the RCC on curved quadratic "
                                                     "elements, the force along the wall's normal, under mesh "
                                                     "refinement"),
           "snap_fit_3d": SNAP_FIT}


def rung(name: str, resolution: float, ranks: int) -> dict:
    """One rung of ladder `name`: its result (run, or read when it exists) as a row."""
    ladder = LADDERS[name]
    out = (OUT / name / f"r{resolution:.4f}").resolve()
    result = read_result(out)
    if result is None or result["status"] != "ok":
        result, _ = run_scene(SCENES / ladder.scene, ranks, out,
                              {"mesh.resolution": resolution, "mesh.max_elements": 10_000_000, **ladder.settings})
    metrics = result["metrics"]
    return {"resolution": resolution, "status": result["status"], "dofs": result["info"].get("dofs"),
            "newton_iterations": metrics.get("newton_iterations"), "wall_time": metrics.get("wall_time_s"),
            **{key: metrics.get(key) for key in ladder.quantities}}


def check_ladder(resolutions) -> None:
    """Refuse three finest resolutions that are not refined by one ratio (Richardson needs it)."""
    finest = sorted(resolutions)[-3:]
    if len(finest) == 3 and not math.isclose(finest[2] / finest[1], finest[1] / finest[0], rel_tol=1e-6):
        raise InputError(f"--resolutions: the three finest ({', '.join(f'{r:g}' for r in finest)}) must be "
                         "refined by one ratio for Richardson extrapolation")


def extrapolation(name: str, rows: list[dict]) -> list[dict]:
    """Per quantity of ladder `name`: the Richardson limit of the three finest ok rungs, its order
    and the finest rung's estimated error (None without three rungs)."""
    ladder = LADDERS[name]
    done = [r for r in sorted(rows, key=lambda r: r["resolution"]) if r["status"] == "ok"]
    check_ladder([r["resolution"] for r in done])
    out = []
    for key, meaning in ladder.quantities.items():
        finest = [r[key] for r in done[-3:]]
        if len(finest) < 3 or any(v is None for v in finest):
            continue
        ratio = done[-1]["resolution"] / done[-2]["resolution"]
        limit, order = richardson(finest, ratio)
        series = [r[key] for r in done]
        series = series[max((i + 1 for i, v in enumerate(series) if v is None), default=0):]  # the rungs after a gap
        error, error_order = finest_error(series, ratio, ladder.order_limit)
        how = "capped" if error is not None and error_order < order else "richardson"
        if error is None:
            error, how = range_error(finest), "range"
        out.append({"quantity": key, "meaning": meaning, "finest": finest[-1], "limit": limit, "order": order,
                    "error": error, "how": how, "spread": spread(finest)})
    return out


def error_text(entry: dict, order_limit: float) -> str:
    """A table cell: the estimated error, and how it was estimated unless by Richardson at the observed order."""
    if entry["error"] is None:
        return "-"
    if entry["how"] == "capped":
        return f"{entry['error']:.2%} (order {order_limit:g}, x{SAFETY_FACTOR:g})"
    if entry["how"] == "range":
        converging = math.isfinite(entry["order"]) and entry["order"] > 0
        return f"{entry['error']:.2%} ({RANGE_FACTOR:g} x spread: " + \
            ("coarser rungs out of step)" if converging else "not monotone)")
    return f"{entry['error']:.2%}"


def report(name: str, rows: list[dict]) -> str:
    """The markdown section of ladder `name`: its rungs, then the extrapolation of each quantity."""
    ladder = LADDERS[name]
    quantities = ladder.quantities
    settings = "".join(f" `--set {key}={value}`" for key, value in ladder.settings.items())
    lines = [f"## {ladder.title}", "",
             f"scenes/{ladder.scene}{settings}. Wall time: the case's own (`wall_time_s`: meshing, forms, solve, "
             "output; process start-up excluded).", "",
             *markdown_table(["resolution", "unknowns", "status", "Newton iterations", "wall time (s)", *quantities],
                             [[f"{r['resolution']:.4g}", r["dofs"], r["status"], r["newton_iterations"],
                               f"{r['wall_time']:.0f}" if r["wall_time"] is not None else "-",
                               *(f"{r[k]:.6g}" if r[k] is not None else "-" for k in quantities)] for r in rows]),
             ""]
    table = extrapolation(name, rows)
    if table:
        lines += [*markdown_table(["quantity", "finest rung", "extrapolated", "observed order",
                                   "estimated error of the finest", f"<= {TARGET:.0%}", "spread of the three finest"],
                                  [[t["meaning"], f"{t['finest']:.6g}", f"{t['limit']:.6g}",
                                    f"{t['order']:.2f}" if math.isfinite(t["order"]) else "- (not monotone)",
                                    error_text(t, ladder.order_limit),
                                    "yes" if t["error"] is not None and t["error"] <= TARGET else "no",
                                    f"{t['spread']:.2%}" if t["spread"] is not None else "-"]
                                   for t in table]),
                  "",
                  "Estimated error, where every rung moves the answer the same way and by less than the "
                  "rung before: |finest - extrapolated| / |extrapolated| at the observed order; where "
                  f"the three finest rungs line up at an order above the discretisation's "
                  f"({ladder.order_limit:g}), {SAFETY_FACTOR:g} |finest - next| / (ratio^{ladder.order_limit:g} - 1) "
                  "/ |finest| (the discretisation's order and a factor of safety of 3, as Roache's grid "
                  "convergence index does). Where the rungs do not converge that way (they alternate, or a "
                  f"coarser rung moves the other way or by less), {RANGE_FACTOR:g} x the spread: Eca and "
                  "Hoekstra's uncertainty for oscillatory convergence, 3 x the range of the values, here over "
                  "the three finest rungs. Spread: (largest - smallest) / finest over the three finest "
                  "rungs.", ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ladder", nargs="+", choices=sorted(LADDERS), default=list(LADDERS),
                        help="the ladders to run (default: all)")
    parser.add_argument("--resolutions", type=float, nargs="+", help="override every chosen ladder's rungs")
    parser.add_argument("--ranks", type=int, default=2)
    args = parser.parse_args(argv)
    try:
        check_ladder(args.resolutions or ())
    except InputError as error:
        parser.error(str(error))
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / "convergence_3d.json"
    everything = json.loads(path.read_text()) if path.exists() else {}  # the other ladders' last rows
    for name in args.ladder:
        rows = everything[name] = []
        for resolution in sorted(args.resolutions or LADDERS[name].resolutions):
            print(f"{name}, resolution {resolution:.4g} ...", flush=True)
            rows.append(rung(name, resolution, args.ranks))
            row = rows[-1]
            print(f"  {row['status']}, {row['dofs']} unknowns, {row['newton_iterations']} Newton iterations, "
                  + ", ".join(f"{key} {row[key]}" for key in LADDERS[name].quantities), flush=True)
            write_json_atomic(path, everything)
            write_text_atomic(OUT / "convergence_3d.md",
                              "\n".join(report(n, everything[n]) for n in LADDERS if n in everything))
    print((OUT / "convergence_3d.md").read_text())
    return 0


if __name__ == "__main__":
    sys.exit(main())
