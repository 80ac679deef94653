"""`femcontact run SCENE.toml`: run one scene and write its case directory.

The case directory holds the resolved scene (`scene.json`), `history.csv` (one row per
converged increment, streamed), `fields.npz` and, written atomically as the very last
thing, `result.json`:
{"status": "ok"|"failed", "reason": str|null, "metrics": {...}, "timings": {...}, "info": {...}}.
Progress goes to standard error (`--quiet` silences it and the summary).
Exit code 0 when ok, 1 when the simulation failed (reason recorded), 2 for bad input.
"""
import sys
import time
import traceback
from pathlib import Path

from femcontact.config.scene import case_id, load_scene
from femcontact.io import write_json_atomic


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


def command(args) -> int:
    from mpi4py import MPI

    from femcontact.scenarios.case import run_case

    scene = load_scene(args.scene, args.set)
    rank = MPI.COMM_WORLD.rank
    case_dir = Path(args.out or Path("results", "run", case_id(scene)))
    if rank == 0:
        case_dir.mkdir(parents=True, exist_ok=True)
        write_json_atomic(case_dir / "scene.json", scene)
    MPI.COMM_WORLD.barrier()
    start = time.perf_counter()
    try:
        result = {"status": "ok", "reason": None,
                  **run_case(scene, case_dir, args.checkpoint, args.restart, quiet=args.quiet)}
    except Exception as error:  # recorded, never a half-written result
        from femcontact.solver.stepping import SimulationFailed

        reason = f"{type(error).__name__}: {error}"
        info = {} if isinstance(error, SimulationFailed) else {"traceback": traceback.format_exc()}
        result = {"status": "failed", "reason": reason, "metrics": {}, "timings": {}, "info": info}
        print(f"femcontact run: case failed: {reason}", file=sys.stderr)
        if "traceback" in info:
            print(info["traceback"], file=sys.stderr)
    result["timings"]["total"] = time.perf_counter() - start
    result["info"]["ranks"] = MPI.COMM_WORLD.size
    if rank == 0:
        write_json_atomic(case_dir / "result.json", result)
        if not args.quiet:
            print_summary(result, case_dir)
    return 0 if result["status"] == "ok" else 1


def print_summary(result: dict, case_dir: Path) -> None:
    print(f"case {case_dir}: {result['status']}" + (f" ({result['reason']})" if result["reason"] else ""))
    for key, value in sorted(result["metrics"].items()):
        if isinstance(value, (int, float, bool, str)):
            print(f"  {key:32s} {value:.6g}" if isinstance(value, float) else f"  {key:32s} {value}")
    print(f"  {'wall time (s)':32s} {result['timings']['total']:.3g}")
