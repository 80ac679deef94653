"""`make bench`: what accuracy costs in time, and what each effect costs, measured in one run.

1. Hertz (reference §5): errors of a and p0 against wall time as the contact zone is
   refined (h_c = a/2.5 ... a/40.5), with the time per phase.
2. The Hertz scene at about 10k dofs with each effect switched on in turn: time per
   increment as a ratio to the frictionless quasi-static scene (an effect not named
   costs nothing), and the thesis wedging scene at about 10k dofs.
3. The study runner's overhead per one-rank case, fresh processes against warm workers
   (runner_overhead.py).
Writes results/bench/bench.md and bench.json; timings are ratios within this run.
"""
import json
import time
from pathlib import Path

from mpi4py import MPI

from femcontact.references.hertz import benchmark_half_width
from femcontact.scenarios import hertz, runner_overhead
from femcontact.config.scene import resolve
from femcontact.solver.stepping import Simulation

OUT = Path("results/bench")


def hertz_table() -> list[dict]:
    a = benchmark_half_width()
    hertz.run(a / 2.5)  # compile the forms once, outside the measurements
    rows = []
    for k in (2, 5, 10, 20, 40):
        result = hertz.run(a / (k + 0.5))
        rows.append({"h_c": a / (k + 0.5), "a_over_h": k + 0.5, **{key: result[key] for key in (
            "error_a", "error_p0", "wall_time", "dofs", "newton_iterations", "contact_nodes")},
            **{f"time_{phase}": value for phase, value in result["timings"].items()}})
    return rows


def wedging_scene(resolution: float) -> dict:
    return resolve({"name": "bench", "dim": 2, "geometry": "peg_in_hole", "effects": ["friction", "plane_strain"],
                    "peg": {"width": 40.0, "length": 10.0, "insertion_depth": 5.0}, "hole": {"width": 40.1},
                    "contact": {"mu": 0.2}, "mesh": {"resolution": resolution},
                    "steps": [{"name": "load", "increments": 5, "force": [-5.0, 1.0]},
                              {"name": "release", "increments": 5}]})


def hertz_with(effects, size_max=1.0, **extra) -> dict:
    """The Hertz scene (h_c = a/10.5) with other effects and a finer far field (~10k dofs)."""
    a = benchmark_half_width()
    data = dict(hertz.scene(a / 10.5, increments=4), effects=effects, **extra)
    data["mesh"] = dict(data["mesh"], size_max=size_max)
    data["rigid_body"] = {"dofs": {"x": "held", "y": "free", "rz": "held"}}
    return resolve(data)


def per_increment(scene: dict) -> dict:
    simulation = Simulation(scene, MPI.COMM_SELF)
    start = time.perf_counter()
    simulation.run()
    elapsed = time.perf_counter() - start
    increments = len(simulation.history)
    return {"dofs": simulation.dofs, "increments": increments, "seconds_per_increment": elapsed / increments,
            "newton_per_increment": sum(r["newton_iterations"] for r in simulation.history) / increments,
            "built": simulation.problem.built}


def effect_costs() -> list[dict]:
    variants = [("Hertz: frictionless, quasi-static", ["plane_strain"], {}),
                ("+ friction", ["friction", "plane_strain"], {}),
                ("+ inertia (rigid body)", ["inertia", "plane_strain"], {}),
                ("+ inertia (both bodies)", ["inertia", "plane_strain"], {"dynamics": {"deformable_inertia": True}}),
                ("+ gravity", ["gravity", "plane_strain"], {}),
                ("+ large strain", ["large_strain", "plane_strain"], {})]
    rows = []
    for name, effects, extra in variants:
        per_increment(hertz_with(effects, size_max=8.0, **extra))  # compile outside the timing
        rows.append({"scene": name, **per_increment(hertz_with(effects, **extra))})
    base = rows[0]["seconds_per_increment"]
    for row in rows:
        row["ratio"] = row["seconds_per_increment"] / base
    per_increment(wedging_scene(0.5))
    rows.append({"scene": "wedging (friction), thesis scene", **per_increment(wedging_scene(1.6))})
    rows[-1]["ratio"] = float("nan")
    return rows


def markdown(hertz_rows, effects_rows) -> str:
    lines = ["# femcontact benchmark", "", "## Hertz: accuracy against wall time (1 rank)", "",
             "| a/h_c | dofs | error a | error p0 | Newton its | wall time (s) | mesh | forms | solve |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in hertz_rows:
        lines.append(f"| {r['a_over_h']} | {r['dofs']} | {100 * r['error_a']:+.2f} % | {100 * r['error_p0']:+.2f} % | "
                     f"{r['newton_iterations']} | {r['wall_time']:.2f} | {r['time_mesh']:.2f} | "
                     f"{r['time_forms']:.2f} | {r['time_solve']:.2f} |")
    lines += ["", "## 2-D cost per load increment and per effect (1 rank)", "",
              "| scene | dofs | Newton its / increment | s / increment | ratio |", "|---|---|---|---|---|"]
    for r in effects_rows:
        lines.append(f"| {r['scene']} | {r['dofs']} | {r['newton_per_increment']:.1f} | "
                     f"{r['seconds_per_increment']:.3f} | {r['ratio']:.2f} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    hertz_rows = hertz_table()
    effects_rows = effect_costs()
    overhead = runner_overhead.measure(OUT / "runner")
    (OUT / "bench.json").write_text(json.dumps({"hertz": hertz_rows, "effects": effects_rows,
                                                "runner_overhead": overhead}, indent=1))
    text = markdown(hertz_rows, effects_rows) + "\n" + runner_overhead.markdown(overhead)
    (OUT / "bench.md").write_text(text)
    print(text)
    print(f"written: {OUT / 'bench.md'}")


if __name__ == "__main__":
    main()
