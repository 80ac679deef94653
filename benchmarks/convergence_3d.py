"""`make convergence_3d`: the 3-D wedging answers under mesh refinement, with their
discretisation error.

scenes/wedging_3d.toml (a rigid peg wedged in a stainless block by a 1000 N mm couple, then
released) run as a whole `mpirun -n 2 femcontact run` process at mesh resolutions LADDER, each
sqrt(2) finer than the last (element sizes / sqrt(2), about 2.7x the unknowns). For each answer
in QUANTITIES: the value on every rung, the Richardson extrapolation of the three finest
(`femcontact.references.richardson`) with its observed order, and the estimated error of the
finest rung, |finest - extrapolated| / |extrapolated|, and the spread of the three finest rungs
(largest - smallest) / finest. A rung whose result.json exists is read,
not run again (delete results/convergence_3d/r<resolution> to re-run it). Writes
results/convergence_3d/convergence_3d.md and .json after every rung.

    python -m benchmarks.convergence_3d [--resolutions 1 1.4142 2 2.8284] [--ranks 2]
"""
import argparse
import math
import sys
from pathlib import Path

from femcontact.errors import InputError
from femcontact.families.repository import SCENES
from femcontact.io import read_result, write_json_atomic, write_text_atomic
from femcontact.outputs.tables import markdown_table
from femcontact.references.richardson import richardson

from benchmarks.whole_process import run_scene

OUT = Path("results/convergence_3d")
LADDER = (1.0, 2 ** 0.5, 2.0, 2 * 2 ** 0.5)
"""Mesh resolutions: 17k to about 280k unknowns."""
QUANTITIES = {
    "residual_force_A": "contact force at A after release (N)",
    "load.contact_A_force": "contact force at A under the couple (N)",
    "tilt_loaded_deg": "tilt under the couple (deg)",
    "tilt_released_deg": "tilt after release (deg)",
    "tilt_change_deg": "tilt change under the couple (deg)",
    "release.contact_B_z": "height of the contact centre B after release (mm)",
}
"""result.json metrics reported, with what they are."""
TARGET = 0.01
"""The discretisation error a published 3-D number should carry at most."""


def rung(resolution: float, ranks: int) -> dict:
    """One rung: its result (run, or read when it exists) as a row."""
    out = (OUT / f"r{resolution:.4f}").resolve()
    result = read_result(out)
    if result is None or result["status"] != "ok":
        result, _ = run_scene(SCENES / "wedging_3d.toml", ranks, out,
                              {"mesh.resolution": resolution, "mesh.max_elements": 10_000_000})
    metrics = result["metrics"]
    return {"resolution": resolution, "status": result["status"], "dofs": result["info"].get("dofs"),
            "newton_iterations": metrics.get("newton_iterations"), "wall_time": metrics.get("wall_time_s"),
            **{key: metrics.get(key) for key in QUANTITIES}}


def check_ladder(resolutions) -> None:
    """Refuse three finest resolutions that are not refined by one ratio (Richardson needs it)."""
    finest = sorted(resolutions)[-3:]
    if len(finest) == 3 and not math.isclose(finest[2] / finest[1], finest[1] / finest[0], rel_tol=1e-6):
        raise InputError(f"--resolutions: the three finest ({', '.join(f'{r:g}' for r in finest)}) must be "
                         "refined by one ratio for Richardson extrapolation")


def extrapolation(rows: list[dict]) -> list[dict]:
    """Per quantity: the Richardson limit of the three finest ok rungs, its order and the finest
    rung's estimated error (None without three rungs)."""
    done = [r for r in sorted(rows, key=lambda r: r["resolution"]) if r["status"] == "ok"]
    check_ladder([r["resolution"] for r in done])
    out = []
    for key, meaning in QUANTITIES.items():
        finest = [r[key] for r in done[-3:]]
        if len(finest) < 3 or any(v is None for v in finest):
            continue
        ratio = done[-1]["resolution"] / done[-2]["resolution"]
        limit, order = richardson(finest, ratio)
        converging = math.isfinite(order) and order > 0
        error = abs(finest[-1] - limit) / abs(limit) if converging and limit else None
        spread = (max(finest) - min(finest)) / abs(finest[-1]) if finest[-1] else None
        out.append({"quantity": key, "meaning": meaning, "finest": finest[-1], "limit": limit, "order": order,
                    "error": error, "spread": spread})
    return out


def report(rows: list[dict]) -> str:
    lines = ["## 3-D wedging under mesh refinement", "",
             "Wall time: the case's own (`wall_time_s`: meshing, forms, solve, output; process start-up excluded).", "",
             *markdown_table(["resolution", "unknowns", "status", "Newton iterations", "wall time (s)",
                              *QUANTITIES],
                             [[f"{r['resolution']:.4g}", r["dofs"], r["status"], r["newton_iterations"],
                               f"{r['wall_time']:.0f}" if r["wall_time"] is not None else "-",
                               *(f"{r[k]:.6g}" if r[k] is not None else "-" for k in QUANTITIES)] for r in rows]),
             ""]
    table = extrapolation(rows)
    if table:
        lines += [*markdown_table(["quantity", "finest rung", "extrapolated", "observed order",
                                   "estimated error of the finest", f"<= {TARGET:.0%}", "spread of the three finest"],
                                  [[t["meaning"], f"{t['finest']:.6g}", f"{t['limit']:.6g}", f"{t['order']:.2f}",
                                    f"{t['error']:.2%}" if t["error"] is not None else "not converging",
                                    "yes" if t["error"] is not None and t["error"] <= TARGET else "no",
                                    f"{t['spread']:.2%}" if t["spread"] is not None else "-"]
                                   for t in table]),
                  "",
                  "Spread: (largest - smallest) / finest over the three finest rungs; where they do not "
                  "converge monotonically (no positive observed order) it is what the mesh still moves the "
                  "answer by, not an error bound.", ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resolutions", type=float, nargs="+", default=LADDER)
    parser.add_argument("--ranks", type=int, default=2)
    args = parser.parse_args(argv)
    try:
        check_ladder(args.resolutions)
    except InputError as error:
        parser.error(str(error))
    OUT.mkdir(parents=True, exist_ok=True)
    rows = []
    for resolution in sorted(args.resolutions):
        print(f"resolution {resolution:.4g} ...", flush=True)
        rows.append(rung(resolution, args.ranks))
        row = rows[-1]
        print(f"  {row['status']}, {row['dofs']} unknowns, {row['newton_iterations']} Newton iterations, "
              f"tilt change {row['tilt_change_deg']}, R_A {row['residual_force_A']}", flush=True)
        write_json_atomic(OUT / "convergence_3d.json", rows)
        write_text_atomic(OUT / "convergence_3d.md", report(rows))
    print(report(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
