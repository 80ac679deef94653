"""Study runner overhead per one-rank case: fresh processes against warm workers, in one run.

The same small study (8 short 2-D wedging cases: scenes/wedging_2d.toml at mesh resolution 0.3,
632 dofs, 2 + 2 increments, mu swept) runs with one job twice: each case in a fresh
`mpirun -n 1 femcontact run` (`workers = false`), then all cases in one warm worker (the default).
A one-case study before them compiles the forms, so neither sweep pays for JIT compilation.

- case time: `femcontact run`'s own timer (result.json timings.total) in the warm worker, where
  nothing is left to import: the work the case needs;
- sweep wall time: from the first case's start to the last one's end (runner.json);
- overhead = (sweep wall time - sum of case times) / sum of case times. A fresh process's
  `timings.total` also holds the imports its solve needs (DOLFINx, gmsh), listed apart.

`python -m benchmarks.runner_overhead` runs this alone; `make bench` includes it.
"""
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

from femcontact.families.repository import SCENES
from femcontact.outputs.tables import markdown_table

SCENE = SCENES / "wedging_2d.toml"
MU = (0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45)
OVERRIDES = '[scene]\nmesh.resolution = 0.3\n"steps.0.increments" = 2\n"steps.1.increments" = 2\n'


def run_study(root: Path, name: str, workers: bool, sweep: str) -> list[dict]:
    """Run a study of the coarse wedging scene (--force, one job); returns its cases' records."""
    shutil.rmtree(root / name, ignore_errors=True)  # only this run's cases (a scene change renames them)
    path = root / f"{name}.toml"
    path.write_text(f'[study]\nname = "{name}"\nscene = "{SCENE}"\njobs = 1\nworkers = {str(workers).lower()}\n'
                    f"{OVERRIDES}{sweep}")
    # env: Python's view of it; MPI started in this process (make bench) added PMIX_* and OMPI_* variables
    # to the C environment, which a child would inherit and its `mpirun` fail on (exit 1, no message)
    subprocess.run([sys.executable, "-m", "femcontact", "study", str(path), "--results", str(root), "--force",
                    "--quiet"], check=True, stdout=subprocess.DEVNULL, env=dict(os.environ))
    records = []
    for case in (root / name / "cases").iterdir():
        result, runner = (json.loads((case / f"{kind}.json").read_text()) for kind in ("result", "runner"))
        if result["status"] != "ok":
            raise RuntimeError(f"runner overhead: case {case} failed: {result['reason']}")
        records.append({"case": case.name, "case_time": result["timings"]["total"], "started": runner["started"],
                        "wall": runner["wall"], "worker": runner.get("worker")})
    return sorted(records, key=lambda record: record["started"])


def overheads(records: list[dict], times: dict) -> dict:
    """Overhead of a sweep (records in start order) against the case times `times` (s, by case id):
    over the whole sweep, and after the first case (which in the warm mode also starts the worker)."""
    work = [times[record["case"]] for record in records]
    ends = [r["started"] + r["wall"] for r in records]
    wall, later = max(ends) - records[0]["started"], max(ends) - ends[0]
    return {"cases": len(records), "sweep_wall": wall, "case_time": sum(r["case_time"] for r in records),
            "imports_in_case": (sum(r["case_time"] for r in records) - sum(work)) / len(records),
            "overhead_per_case": (wall - sum(work)) / len(records), "overhead": (wall - sum(work)) / sum(work),
            "later_per_case": (later - sum(work[1:])) / (len(records) - 1),
            "later": (later - sum(work[1:])) / sum(work[1:])}


def measure(root: Path = Path("results/bench/runner")) -> dict:
    """Sweep wall time, case times and overhead per mode (s), fresh and warm, measured in this run."""
    root.mkdir(parents=True, exist_ok=True)
    run_study(root, "warmup", False, "")  # compiles the forms into the job slot's JIT cache
    sweep = f'[sweep]\ngrid = {{ "contact.mu" = {list(MU)} }}\n'
    fresh, warm = run_study(root, "fresh", False, sweep), run_study(root, "warm", True, sweep)
    times = {record["case"]: record["case_time"] for record in warm}
    modes = {"fresh": {**overheads(fresh, times), "processes": len(fresh)},
             "warm": {**overheads(warm, times), "processes": len({r["worker"] for r in warm})}}
    modes["ratio"] = modes["fresh"]["overhead_per_case"] / modes["warm"]["overhead_per_case"]
    return modes


def markdown(modes: dict) -> str:
    rows = [[label, m["processes"], m["sweep_wall"], m["case_time"], m["imports_in_case"], m["overhead_per_case"],
             100 * m["overhead"], m["later_per_case"], 100 * m["later"]]
            for label, m in (("fresh `mpirun -n 1` per case", modes["fresh"]), ("warm worker", modes["warm"]))]
    lines = ["## Study runner overhead per one-rank case (1 job)", "",
             f"{modes['fresh']['cases']} 2-D wedging cases (632 dofs, 4 increments); case time = `femcontact run`'s "
             "timer in a warm worker; overhead = (sweep wall - sum of case times) / sum of case times; "
             "'later cases': from the end of the first case (the warm worker starts with the first).", "",
             *markdown_table(["mode", "processes", "sweep wall (s)", "sum of case times (s)",
                              "imports inside the case (s/case)", "overhead (s/case)", "overhead",
                              "later cases: overhead (s/case)", "later cases: overhead"], rows,
                             formats=[None, None, "{:.2f}", "{:.2f}", "{:.2f}", "{:.3f}", "{:.1f} %", "{:.3f}", "{:.1f} %"]),
             "", f"Overhead per case, fresh / warm: {modes['ratio']:.1f}x."]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    result = measure()
    Path("results/bench/runner_overhead.json").write_text(json.dumps(result, indent=1))
    print(markdown(result))
