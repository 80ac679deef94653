"""`femcontact run SCENE.toml`: run one scene and write its case directory.

The case directory holds the resolved scene (`scene.json`), `history.csv` (one row per
converged increment, streamed), `fields.npz` and, written atomically as the very last
thing, `result.json`:
{"status": "ok"|"no_equilibrium"|"failed", "reason": str|null, "metrics": {...}, "timings": {...}, "info": {...}}.
`no_equilibrium`: a load of a 2-D rigid peg in two-point contact that no static equilibrium can
carry (it needs more friction than mu): the reason names the step, the load and the friction it
needs; the metrics are those of the converged increments (a peg in a hole: not wedged). With
`inertia` the load runs on until the peg leaves contact, comes to rest or the step ends
(metric `run_on`).
A metric that is undefined (NaN or infinite) is written as null and listed in
`info.undefined_metrics`. Progress goes to standard error (`--quiet` silences it and the summary).
Exit code 0 when ok or no_equilibrium, 1 when the simulation failed (reason recorded), 2 for bad input or an
output directory that cannot be written (one message naming it); input found bad only once the
model is built (a `steps[].stop.column` that names no history column) is refused the same way,
before the first increment, and leaves no case directory behind.
"""
import json
import math
import os
import shutil
import sys
import time
import traceback
from pathlib import Path

from femcontact.config.scene import case_id, load_scene
from femcontact.process import start_mpi_for_meshing
from femcontact.errors import InputError
from femcontact.io import WriteError, describe, make_dir, remove_stale_compilations, write_json_atomic
from femcontact.outputs.result import ANSWERS

STALE_COMPILATION_AGE = 600.0  # s; a form compiles in well under a minute
_CLEANED_CACHES = set()  # JIT caches this process has cleaned (a study's warm worker runs many cases)


def add_arguments(parser):
    parser.add_argument("scene", help="scene file (TOML)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="override a scene value, e.g. --set peg.insertion_depth=5")
    parser.add_argument("--out", default=None, help="case directory (default results/run/<case id>)")
    parser.add_argument("--quiet", action="store_true", help="no progress and no summary table")
    parser.add_argument("--checkpoint", action="store_true",
                        help="save the state after the last step in OUT/checkpoint/ (shared prefix of a study)")
    parser.add_argument("--restart", default=None, metavar="CHECKPOINT",
                        help="start from a checkpoint directory written by --checkpoint and run only the "
                             "steps after the ones it holds")


def check_restart(scene: dict, checkpoint: bool, restart, ranks: int) -> None:
    """Refuse --checkpoint/--restart requests that cannot work, before anything is written."""
    if scene["kind"] == "rcc" and (checkpoint or restart):
        raise InputError("--checkpoint/--restart: an rcc case has no steps to share")
    if restart is None:
        return
    path = Path(restart) / "checkpoint.json"
    try:
        meta = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise InputError(f"--restart {restart}: no readable checkpoint ({path}: "
                         f"{getattr(error, 'strerror', None) or error})") from None
    if meta.get("ranks") != ranks:
        raise InputError(f"--restart {restart}: written on {meta.get('ranks')} ranks, run on {ranks}")
    if not 0 < meta.get("steps", 0) < len(scene["steps"]):
        raise InputError(f"--restart {restart}: holds {meta.get('steps')} step(s); the scene has "
                         f"{len(scene['steps'])}, so no later step would run")


def command(args) -> int:
    scene = load_scene(args.scene, args.set)  # bad input is refused before MPI starts
    MPI = start_mpi_for_meshing()
    from femcontact.scenarios.case import run_case

    comm = MPI.COMM_WORLD
    check_restart(scene, args.checkpoint, args.restart, comm.size)
    cache = jit_cache()
    if comm.rank == 0 and cache not in _CLEANED_CACHES:
        # a compilation unfinished for 10 minutes was killed: FFCx would wait for it forever (once per
        # process: a compilation of this process's own finishes or takes the process with it)
        remove_stale_compilations(cache, older_than=STALE_COMPILATION_AGE)
        _CLEANED_CACHES.add(cache)
    case_dir = Path(args.out or Path("results", "run", case_id(scene)))
    problem, created = None, not case_dir.exists()
    if comm.rank == 0:
        try:
            make_dir(case_dir)
            (case_dir / "result.json").unlink(missing_ok=True)  # a stale result must not outlive this run
            write_json_atomic(case_dir / "scene.json", scene)
        except (WriteError, OSError) as error:
            problem = error if isinstance(error, WriteError) else WriteError(describe(error, case_dir))
    problem = comm.bcast(problem, root=0)
    if problem is not None:
        raise problem
    start = time.perf_counter()
    try:
        result = {"status": "ok", "reason": None,
                  **run_case(scene, case_dir, args.checkpoint, args.restart, quiet=args.quiet)}
    except InputError as error:  # found once the model is built (a history column): refused, nothing left
        if comm.rank == 0:
            withdraw(case_dir, created)
        raise InputError(f"{args.scene}: {error}") from None
    except Exception as error:  # recorded, never a half-written result
        from femcontact.solver.stepping import SimulationFailed

        clear = isinstance(error, (SimulationFailed, WriteError))  # their message says it all
        reason = str(error) if isinstance(error, WriteError) else f"{type(error).__name__}: {error}"
        info = {} if clear else {"traceback": traceback.format_exc()}
        result = {"status": "failed", "reason": reason, "metrics": {}, "timings": {}, "info": info}
        print(f"femcontact run: case failed: {reason}", file=sys.stderr)
        if "traceback" in info:
            print(info["traceback"], file=sys.stderr)
    result["timings"]["total"] = time.perf_counter() - start
    result["info"]["ranks"] = comm.size
    result["info"]["undefined_metrics"] = sorted(  # written as null: e.g. a contact centre without contact
        name for name, value in result["metrics"].items() if isinstance(value, float) and not math.isfinite(value))
    if comm.rank == 0:
        write_json_atomic(case_dir / "result.json", result)
        if not args.quiet:
            print_summary(result, case_dir)
    return 0 if result["status"] in ANSWERS else 1


def withdraw(case_dir: Path, created: bool) -> None:
    """Remove what a refused run wrote: the case directory if it made it, else its files."""
    if created:
        shutil.rmtree(case_dir, ignore_errors=True)
        return
    for name in ("scene.json", "history.csv"):
        (case_dir / name).unlink(missing_ok=True)


def jit_cache() -> Path:
    """FFCx's JIT cache directory ($XDG_CACHE_HOME/fenics, default ~/.cache/fenics)."""
    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"), "fenics")


def print_summary(result: dict, case_dir: Path) -> None:
    print(f"case {case_dir}: {result['status']}" + (f" ({result['reason']})" if result["reason"] else ""))
    for key, value in sorted(result["metrics"].items()):
        if isinstance(value, (int, float, bool, str)):
            print(f"  {key:32s} {value:.6g}" if isinstance(value, float) else f"  {key:32s} {value}")
    print(f"  {'wall time (s)':32s} {result['timings']['total']:.3g}")
