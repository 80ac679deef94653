"""`make bench_solvers`: how a Newton iteration's time and memory grow with the unknowns, for the
direct and the iterative linear solver (`solver.linear`), on 1 and 2 ranks.

The scene is scenes/wedging_3d.toml (a rigid peg wedged in a stainless block by a moment) at
mesh resolutions RESOLUTIONS, its first load increment, with the contact force along the peg's
normal (`contact.normal = "body"`, the measured rows' setting). Each (resolution, solver, ranks) is one
`mpirun -n R python -m benchmarks.solver_scaling --worker RES SOLVER` process: it meshes the
scene, takes ITERATIONS Newton iterations (assembly, linear solves, line search) and reports
the unknowns, the first iteration's time (with the factorisation or the multigrid set-up), the
mean time of the later ones and of their parts (`PARTS`), the residual they reach (the solvers
must agree on it) and the peak memory summed over the ranks. The exponent p of time ~ n^p (and
of memory) is fitted by least squares over the rungs from FIT_FROM unknowns, and the goals are
checked. A rung whose memory, predicted from the last smaller one, exceeds what the machine has
available is skipped with a message (the direct solver at 1M unknowns).
Writes results/bench/solvers.md and solvers.json, a row at a time (a killed run keeps the rows
it measured; a new measurement replaces its row).

    python -m benchmarks.solver_scaling [--resolutions 1 2 3] [--solvers direct iterative] [--ranks 1 2]
"""
import argparse
import json
import math
import resource
import sys
import time
from pathlib import Path

import numpy as np

from femcontact.families.repository import SCENES
from femcontact.io import write_json_atomic, write_text_atomic

from benchmarks.bench import OUT, _run

SCENE = SCENES / "wedging_3d.toml"
RESOLUTIONS = (1.0, 2.0, 2.6, 3.3, 4.4)
"""Mesh resolutions: 17k, 109k, 227k, 447k and about 1.03M unknowns."""
ITERATIONS = 4
"""Newton iterations timed per process."""
FIT_FROM = 100_000
"""Unknowns from which the exponent of the time per iteration is fitted."""
MAX_ELEMENTS = 10_000_000
"""`mesh.max_elements` of the runs (the finest rung is estimated at 4.8 million elements)."""
EXPONENT_GOAL = 1.2
"""Largest exponent p of the iterative solver's time per Newton iteration ~ n^p from FIT_FROM unknowns."""
MEMORY_GOAL = 16.0
"""Largest peak memory (GB, summed over 2 ranks) of the iterative solver at 1M unknowns."""
SPEEDUP_GOAL = 1.7
"""Least speed-up of 2 ranks over 1 on the later iterations, from SPEEDUP_FROM unknowns."""
SPEEDUP_FROM = 200_000
MEMORY_GROWTH = 1.7
"""Exponent of memory ~ n^p by which a rung is skipped when its predicted memory exceeds what is
available (the direct solver's measured 1.66 from 109k to 447k unknowns on one rank)."""
PARTS = ("factor or update", "linear solves", "residual assemblies")
"""The parts of a later Newton iteration timed apart (the slowest rank's; the rest is the
Jacobian's assembly, the rigid rows and the dense Schur step): the linear solver's `factor` (the
direct solver's contact update, or the multigrid set-up), its `solve` calls and the residual
assemblies (one per line-search trial)."""
LOAD_STEP = {"name": "load", "increments": 1, "moment": [0.0, -200.0, 0.0]}
"""The timed increment: a fifth of the scene's moment, in one increment."""


def measure(resolution: float, solver: str) -> dict:
    """ITERATIONS Newton iterations of the scene's first increment on every rank (this process
    under mpirun); times in s, memory in bytes summed over the ranks."""
    from mpi4py import MPI

    from femcontact.api import load_scene
    from femcontact.solver.stepping import Simulation

    comm = MPI.COMM_WORLD
    scene = load_scene(SCENE, {"mesh.resolution": resolution, "mesh.max_elements": MAX_ELEMENTS,
                               "solver.linear": solver, "steps": [LOAD_STEP], "contact.normal": "body"})
    start = time.perf_counter()
    simulation = Simulation(scene, comm)
    setup = time.perf_counter() - start
    newton, step = simulation.newton, simulation.schedule.steps[0]
    load = simulation.schedule.load(0, step["duration"], step["duration"])
    simulation.problem.begin_increment(load)
    simulation.prescribe(load)
    residual = newton.assemble_residual(load)
    parts, later = dict.fromkeys(PARTS, 0.0), False

    def timed(function, part):  # adds the call's time to `part` during the later iterations
        def call(*args, **kwargs):
            start = time.perf_counter()
            try:
                return function(*args, **kwargs)
            finally:
                if later:
                    parts[part] += time.perf_counter() - start
        return call

    newton.linear.factor = timed(newton.linear.factor, "factor or update")
    newton.linear.solve = timed(newton.linear.solve, "linear solves")
    newton.assemble_residual = timed(newton.assemble_residual, "residual assemblies")
    times = []
    for iteration in range(ITERATIONS):
        later = iteration > 0
        comm.barrier()
        start = time.perf_counter()
        du, dr = newton.direction(load, residual[0], residual[1])
        residual = newton.line_search(load, du, dr, residual)
        newton.release_dropped()
        times.append(comm.allreduce(time.perf_counter() - start, op=MPI.MAX))
    memory = comm.allreduce(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024, op=MPI.SUM)
    return {"resolution": resolution, "solver": solver, "ranks": comm.size,
            "dofs": simulation.dofs, "setup": setup, "first": times[0], "next": sum(times[1:]) / (len(times) - 1),
            "residual": float(newton.norm(residual[0], residual[1])), "memory": memory,
            "parts": {part: comm.allreduce(seconds, op=MPI.MAX) / (ITERATIONS - 1) for part, seconds in parts.items()}}


def run(resolution: float, solver: str, ranks: int) -> dict | None:
    """One measurement as a whole process; None (reason on stderr) when it fails."""
    return _run(["mpirun", "-n", str(ranks), sys.executable, "-m", "benchmarks.solver_scaling",
                 "--worker", str(resolution), solver])


def predicted_memory(rows: list[dict], resolution: float, solver: str, ranks: int) -> float:
    """Peak memory (bytes) of a run at `resolution` from the largest smaller rung measured with
    the same solver and ranks: memory ~ n^MEMORY_GROWTH, n ~ resolution^3; 0 without one."""
    smaller = [r for r in rows if r["solver"] == solver and r["ranks"] == ranks and r["resolution"] < resolution]
    if not smaller:
        return 0.0
    last = max(smaller, key=lambda r: r["resolution"])
    return last["memory"] * (resolution / last["resolution"]) ** (3 * MEMORY_GROWTH)


def available_memory() -> float:
    """The memory (bytes) the kernel says is available now (/proc/meminfo MemAvailable)."""
    for line in Path("/proc/meminfo").read_text().splitlines():
        if line.startswith("MemAvailable:"):
            return float(line.split()[1]) * 1024
    return math.inf


def exponent(rows: list[dict], key: str) -> float | None:
    """Least-squares slope of log(rows[key]) against log(dofs); None below two rows."""
    if len(rows) < 2:
        return None
    return float(np.polyfit(np.log([r["dofs"] for r in rows]), np.log([r[key] for r in rows]), 1)[0])


def ladder(rows: list[dict], solver: str, ranks: int) -> list[dict]:
    """The rows of one solver on `ranks` ranks from FIT_FROM unknowns, by size."""
    return sorted((r for r in rows if r["solver"] == solver and r["ranks"] == ranks and r["dofs"] >= FIT_FROM),
                  key=lambda r: r["dofs"])


def goals(rows: list[dict]) -> list[list]:
    """[goal, measured, ratio to goal, holds] of the iterative solver, as measured in `rows`."""
    out = []
    for ranks in (1, 2):
        rungs = ladder(rows, "iterative", ranks)
        p = exponent(rungs, "next")
        if p is not None:
            out.append([f"time per Newton iteration ~ n^p with p <= {EXPONENT_GOAL} from {FIT_FROM:,} unknowns, "
                        f"iterative, {ranks} rank(s)", f"p = {p:.2f} ({rungs[0]['dofs']:,} to {rungs[-1]['dofs']:,})",
                        f"{p / EXPONENT_GOAL:.2f}", "yes" if p <= EXPONENT_GOAL else "no"])
    largest = ladder(rows, "iterative", 2)[-1:]
    if largest and largest[0]["dofs"] >= 1_000_000:
        memory = largest[0]["memory"] / 1e9
        out.append([f"memory <= {MEMORY_GOAL:g} GB at 1M unknowns, 2 ranks", f"{memory:.2f} GB at {largest[0]['dofs']:,}",
                    f"{memory / MEMORY_GOAL:.2f}", "yes" if memory <= MEMORY_GOAL else "no"])
    for solver in ("iterative", "direct"):
        for one in ladder(rows, solver, 1):
            two = next((r for r in ladder(rows, solver, 2) if r["resolution"] == one["resolution"]), None)
            if two is not None and one["dofs"] >= SPEEDUP_FROM:
                speedup = one["next"] / two["next"]
                out.append([f"2 ranks >= {SPEEDUP_GOAL}x as fast as 1 from {SPEEDUP_FROM:,} unknowns, {solver}, "
                            "later iterations", f"{speedup:.2f}x at {one['dofs']:,}", f"{speedup / SPEEDUP_GOAL:.2f}",
                            "yes" if speedup >= SPEEDUP_GOAL else "no"])
    return out


def report(rows: list[dict]) -> str:
    """The table, the fitted exponents and the goals (markdown)."""
    from femcontact.outputs.tables import markdown_table

    lines = ["## Linear solvers: a Newton iteration of the 3-D wedging scene against the unknowns", "",
             *markdown_table(["solver", "ranks", "resolution", "unknowns", "first iteration (s)",
                              "later iterations (s)", f"residual after {ITERATIONS} (N)", "memory (GB)"],
                             [[r["solver"], r["ranks"], r["resolution"], r["dofs"], f"{r['first']:.2f}",
                               f"{r['next']:.2f}", f"{r['residual']:.6e}", f"{r['memory'] / 1e9:.2f}"] for r in rows]),
             ""]
    for solver in sorted({r["solver"] for r in rows}):
        for ranks in sorted({r["ranks"] for r in rows}):
            rungs = ladder(rows, solver, ranks)
            for key, name in (("first", "first iteration"), ("next", "later iterations")):
                p = exponent(rungs, key)
                if p is not None:
                    lines.append(f"- {solver}, {ranks} rank(s), {name}: time ~ n^{p:.2f} "
                                 f"from {rungs[0]['dofs']:,} to {rungs[-1]['dofs']:,} unknowns")
            p = exponent(rungs, "memory")
            if p is not None:
                lines.append(f"- {solver}, {ranks} rank(s), memory ~ n^{p:.2f}")
    timed = [r for r in rows if "parts" in r]
    if timed:
        lines += ["", "A later Newton iteration by part (s, the slowest rank's; the rest: the Jacobian's assembly, "
                  "the rigid rows and the dense Schur step):", "",
                  *markdown_table(["solver", "ranks", "unknowns", "later iteration", *PARTS],
                                  [[r["solver"], r["ranks"], r["dofs"], f"{r['next']:.2f}",
                                    *(f"{r['parts'][part]:.2f}" for part in PARTS)] for r in timed])]
    table = goals(rows)
    if table:
        lines += ["", *markdown_table(["goal", "measured", "ratio to goal", "holds"], table)]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resolutions", type=float, nargs="+", default=RESOLUTIONS)
    parser.add_argument("--solvers", nargs="+", default=["direct", "iterative"], choices=["direct", "iterative"])
    parser.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--worker", nargs=2, metavar=("RESOLUTION", "SOLVER"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        result = measure(float(args.worker[0]), args.worker[1])
        from mpi4py import MPI
        if MPI.COMM_WORLD.rank == 0:
            print(json.dumps(result))
        return 0
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / "solvers.json"
    rows = json.loads(path.read_text()) if path.exists() else []  # a new measurement replaces its row
    for resolution in args.resolutions:
        for solver in args.solvers:
            for ranks in args.ranks:
                print(f"resolution {resolution}, {solver}, {ranks} rank(s) ...", flush=True)
                needed = predicted_memory(rows, resolution, solver, ranks)
                if needed > available_memory():
                    print(f"  skipped: about {needed / 1e9:.0f} GB needed (from the last smaller rung, memory "
                          f"~ n^{MEMORY_GROWTH}), {available_memory() / 1e9:.0f} GB available", flush=True)
                    continue
                row = run(resolution, solver, ranks)
                if row is None:
                    continue
                print(f"  {row['dofs']} unknowns: first {row['first']:.2f} s, later {row['next']:.2f} s, "
                      f"residual {row['residual']:.6e} N, {row['memory'] / 1e9:.2f} GB", flush=True)
                rows = sorted([r for r in rows if (r["resolution"], r["solver"], r["ranks"]) !=
                               (row["resolution"], row["solver"], row["ranks"])] + [row],
                              key=lambda r: (r["solver"], r["ranks"], r["dofs"]))
                write_json_atomic(path, rows)
                write_text_atomic(OUT / "solvers.md", report(rows))
    print(report(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
