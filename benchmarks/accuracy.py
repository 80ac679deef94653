"""`make accuracy`: what accuracy costs in time, measured in one run.

For each knob a user can turn, error against wall time (mesh, forms, solve and
measurement of one case in this process; Python start-up excluded, forms compiled
beforehand so the JIT cache is warm):

- Hertz (docs/references.md, analytic reference): contact-zone size (levels 0-4, a/h_c =
  2^(L+1) + 0.5), element degree P1/P2, the Nitsche parameter gamma, Newton rtol;
- 2-D wedging (scenes/wedging_2d.toml, l_d = 5): mesh resolution, against a Richardson
  extrapolation of the three finest resolutions, for the residual force R_A after release
  and the released tilt;
- dislodging (scenes/dislodging_2d.toml, thesis case 1, 50 Hz pulses): threshold peak force,
  impulse at the threshold and at 1.05 x the pull-out against dt_max and mesh resolution
  (`femcontact.families.dislodging.accuracy`);
- 3-D wedging (scenes/wedging_3d.toml, 2 ranks, `--with-3d`): resolution, against the finest;
- the presets `accuracy = fast | balanced | accurate` on both 2-D problems;
- 2-D insertion (scenes/insertion_2d.toml; rows from femcontact.families.insertion.metrics): the in-hole
  peak insertion force and the two-point onset against resolution, load increments and rtol.

Each problem is one entry of `PROBLEMS`: a function returning its rows (and notes), the
error columns of its table and its Pareto plots (an `Accuracy`). A study family adds its rows
by declaring its `accuracy` (femcontact.families), the function in the family's own package. Writes
results/accuracy/accuracy.md, accuracy.json and one Pareto plot per problem (error
against wall time, one marker per setting, the Pareto front joined).
"""
import argparse
import importlib
import json
import math
import sys
import time
from pathlib import Path

from femcontact.config.presets import PRESETS
from femcontact.families import FAMILIES, Accuracy
from femcontact.families.repository import SCENES
from femcontact.outputs.tables import markdown_table
from femcontact.references.richardson import richardson

from benchmarks.whole_process import run_scene

PRESET_NAMES = ("fast", "balanced", "accurate")
OUT = Path("results/accuracy")


def hertz_case(label: str, knob: str, contact_size: float, degree: int = 1, gamma: float = 10.0,
               rtol: float | None = None, resolution: float = 1.0) -> dict:
    from femcontact.families.hertz import benchmark as hertz
    from femcontact.solver.stepping import Simulation

    start = time.perf_counter()
    data = hertz.scene(contact_size, gamma=gamma, degree=degree)
    data["mesh"]["resolution"] = resolution
    if rtol is not None:
        data["solver"]["rtol"] = rtol
    simulation = Simulation(data)
    simulation.run()
    measured = hertz.measure(simulation)
    wall = time.perf_counter() - start
    a, p0 = hertz.reference(data)
    return {"knob": knob, "setting": label, "dofs": simulation.dofs, "wall_time": wall,
            "newton_iterations": sum(r["newton_iterations"] for r in simulation.history),
            "error_a": abs(measured["a"] / a - 1), "error_p0": abs(measured["p0"] / p0 - 1)}


def hertz_rows() -> tuple[list[dict], list[str]]:
    from femcontact.references.hertz import benchmark_half_width

    a = benchmark_half_width()
    size = lambda level: a / (2 ** (level + 1) + 0.5)
    hertz_case("warm-up", "", size(0))
    hertz_case("warm-up", "", size(0), degree=2)
    rows = [hertz_case(f"P1 level {level}", "mesh (P1)", size(level)) for level in range(5)]
    rows += [hertz_case(f"P2 level {level}", "degree P2", size(level), degree=2) for level in range(4)]
    rows += [hertz_case(f"gamma {gamma:g}, level 2", "Nitsche gamma", size(2), gamma=gamma) for gamma in (1.0, 100.0)]
    rows += [hertz_case(f"rtol {rtol:g}, level 2", "Newton rtol", size(2), rtol=rtol) for rtol in (1e-6, 1e-11)]
    rows += [hertz_case(f"preset {name}", "preset", size(1), resolution=PRESETS[name]["mesh"]["resolution"],
                        rtol=PRESETS[name]["solver"]["rtol"]) for name in PRESET_NAMES]
    return rows, []


def wedging_case(resolution: float | None, label: str, knob: str, overrides=()) -> dict:
    """One wedging run; `resolution` None leaves the mesh to the scene (and its preset)."""
    from femcontact.families import load_scene
    from femcontact.families.wedging.metrics import wedge_metrics
    from femcontact.solver.stepping import Simulation

    start = time.perf_counter()
    mesh = [] if resolution is None else [f"mesh.resolution={resolution}"]
    scene = load_scene(SCENES / "wedging_2d.toml", [*mesh, *overrides])
    simulation = Simulation(scene)
    simulation.run()
    metrics = wedge_metrics(simulation)
    return {"knob": knob, "setting": label, "resolution": scene["mesh"]["resolution"],
            "dofs": simulation.dofs, "wall_time": time.perf_counter() - start,
            "newton_iterations": sum(r["newton_iterations"] for r in simulation.history),
            "residual_force_A": metrics["residual_force_A"], "tilt_released_deg": metrics["tilt_released_deg"]}


def wedging_rows() -> tuple[list[dict], list[str]]:
    wedging_case(0.35, "warm-up", "")
    resolutions = (0.35, 0.5, 0.7, 1.0, 1.4, 2.0, 2.8)
    rows = [wedging_case(r, f"resolution {r:g}", "mesh (P1)") for r in resolutions]
    rows += [wedging_case(None, f"preset {name}", "preset", [f"accuracy={name}"]) for name in PRESET_NAMES]
    finest = rows[len(resolutions) - 3: len(resolutions)]
    notes = []
    for key in ("residual_force_A", "tilt_released_deg"):
        reference, order = richardson([r[key] for r in finest], 2.8 / 2.0)
        for row in rows:
            row[f"error_{key}"] = abs(row[key] / reference - 1)
        how = (f"Richardson extrapolation of resolutions 1.4, 2.0, 2.8 (observed order {order:.2f})"
               if math.isfinite(order) and order > 0 else
               f"the finest resolution, 2.8 (no Richardson: the three finest values do not converge "
               f"monotonically, observed order {order:.2f})")
        notes.append(f"Reference for {key}: {reference:.6g}, from {how}.")
    return rows, notes


WEDGING_3D_SETTINGS = [("mesh (P1, 2 ranks)", f"resolution {r:g}", {"mesh.resolution": r}) for r in (0.3, 0.4, 0.55, 0.75)] + [
    ("load increments (resolution 0.55)", f"{n} increments", {"mesh.resolution": 0.55, "steps.0.increments": n})
    for n in (10, 20)]
"""(knob, setting, scene overrides) of the 3-D wedging rows; the scene loads in 5 increments."""


def wedging_3d_rows() -> tuple[list[dict], list[str]]:
    rows = []
    for knob, setting, overrides in WEDGING_3D_SETTINGS:
        out = (OUT / f"wedging_3d_{setting.replace(' ', '_')}").resolve()
        result, wall = run_scene(SCENES / "wedging_3d.toml", 2, out, overrides)
        rows.append({"knob": knob, "setting": setting, "wall_time": wall, "status": result["status"],
                     "dofs": result["info"].get("dofs"), "newton_iterations": result["info"].get("newton_iterations"),
                     "resultant": result["metrics"].get("residual_force_A")})
    reference = next(row["resultant"] for row in rows if row["setting"] == "resolution 0.75")
    for row in rows:
        ok = row["resultant"] is not None and reference
        row["error_resultant"] = abs(row["resultant"] / reference - 1) if ok else float("nan")
    return rows, ["Reference for the resultant: the finest resolution, 0.75 (5 load increments)."]


PROBLEMS = {
    "hertz": Accuracy("benchmarks.accuracy:hertz_rows", ("error_a", "error_p0"),
                     (("error_a", "Hertz: contact half-width a"), ("error_p0", "Hertz: peak pressure p0"))),
    "wedging_2d": Accuracy("benchmarks.accuracy:wedging_rows",
                          ("error_residual_force_A", "error_tilt_released_deg"),
                          (("error_residual_force_A", "2-D wedging: residual force R_A after release"),)),
    "wedging_3d": Accuracy("benchmarks.accuracy:wedging_3d_rows", ("error_resultant",),
                          (("error_resultant", "3-D wedging: contact resultant after release"),), default=False),
    **{family.name: family.accuracy for family in FAMILIES if family.accuracy},
}
"""The problems measured: those of this module, then every study family's own rows (its `accuracy`)."""


def measure(name: str) -> tuple[list[dict], list[str]]:
    """Rows and notes of one problem, each row tagged with the problem's name."""
    module, function = PROBLEMS[name].rows.split(":")
    rows, notes = getattr(importlib.import_module(module), function)()
    for row in rows:
        row["problem"] = name
    return rows, notes


def pareto_plot(rows: list[dict], error: str, title: str, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    points = [(r["wall_time"], r[error], r["knob"], r["setting"]) for r in rows
              if r.get(error) and math.isfinite(r[error]) and r[error] > 0]
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for knob in dict.fromkeys(p[2] for p in points):
        xs, ys = zip(*[(p[0], p[1]) for p in points if p[2] == knob])
        ax.scatter(xs, ys, label=knob, s=30)
    front, best = [], math.inf
    for t, e, *_ in sorted(points):
        if e < best:
            front.append((t, e))
            best = e
    if front:
        ax.plot(*zip(*front), "k--", lw=1, label="Pareto front")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time of the case (s)")
    ax.set_ylabel(f"relative error ({error.removeprefix('error_')})")
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def markdown(results: dict) -> str:
    """The report: one table per measured problem, then its notes."""
    lines = ["# What accuracy costs in time", "",
             "Measured in one run of `make accuracy` (one process, forms compiled beforehand; wall time = mesh +",
             "forms + solve + measurement of the case).", ""]
    for name, (rows, notes) in results.items():
        errors = PROBLEMS[name].errors
        lines += [f"## {name}", "", *markdown_table(
            ["knob", "setting", "dofs", "Newton its", "wall time (s)", *errors],
            [[r["knob"], r["setting"], r.get("dofs", ""), r.get("newton_iterations", ""), r["wall_time"],
              *(100 * r[e] for e in errors)] for r in rows],
            formats=[None] * 4 + ["{:.2f}"] + ["{:.3f} %"] * len(errors))]
        lines += ["", *notes, ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.accuracy", description=__doc__.splitlines()[0])
    parser.add_argument("--problems", default=",".join(n for n, p in PROBLEMS.items() if p.default),
                        help=f"comma-separated problems to measure, from {', '.join(PROBLEMS)} (default: %(default)s)")
    parser.add_argument("--with-3d", action="store_true", help="also the 3-D wedging case on 2 ranks")
    args = parser.parse_args(argv)
    names = [n.strip() for n in args.problems.split(",") if n.strip()] + (["wedging_3d"] * args.with_3d)
    unknown = [n for n in names if n not in PROBLEMS]
    if unknown:
        parser.error(f"--problems: unknown problem {unknown[0]!r}; known: {', '.join(PROBLEMS)}")
    OUT.mkdir(parents=True, exist_ok=True)
    results = {}
    for name in dict.fromkeys(names):
        results[name] = measure(name)
        print(markdown({name: results[name]}), flush=True)
        for error, title in PROBLEMS[name].plots:
            pareto_plot(results[name][0], error, title, OUT / f"pareto_{name}_{error.removeprefix('error_')}.png")
    (OUT / "accuracy.json").write_text(json.dumps({n: {"rows": r, "notes": t} for n, (r, t) in results.items()},
                                                  indent=1))
    text = markdown(results)
    (OUT / "accuracy.md").write_text(text)
    print(f"written: {OUT / 'accuracy.md'}, accuracy.json and the Pareto plots in {OUT}/")
    return 0


if __name__ == "__main__":
    from femcontact.process import quiet_logging

    quiet_logging()
    sys.exit(main())
