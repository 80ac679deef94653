"""`femcontact run SCENE.toml`: run one scene and write its case directory.

The case directory holds `scene.toml`'s resolved form (`scene.json`), a log and,
written atomically as the very last thing, `result.json`:
{"status": "ok"|"failed", "reason": str|null, "metrics": {...}, "timings": {...}, "info": {...}}.
Exit code 0 when ok, 1 when the simulation failed (reason recorded), 2 for bad input.
"""
import json
import os
import sys
import time
import traceback
from pathlib import Path

from femcontact.errors import InputError
from femcontact.scene import case_id, load_scene


def add_arguments(parser):
    parser.add_argument("scene", help="scene file (TOML)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="override a scene value, e.g. --set peg.insertion_depth=5")
    parser.add_argument("--out", default=None, help="case directory (default results/run/<case id>)")
    parser.add_argument("--quiet", action="store_true", help="no summary table")
    parser.add_argument("--checkpoint", action="store_true",
                        help="save the state after the last step in OUT/checkpoint/ (shared prefix of a study)")
    parser.add_argument("--restart", default=None, metavar="CHECKPOINT",
                        help="start from a checkpoint directory written by --checkpoint and run only the "
                             "steps after the ones it holds")


def write_json_atomic(path: Path, data) -> None:
    """Write JSON to a temporary file, fsync it, then rename it into place."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "w") as stream:
        json.dump(data, stream, indent=1, sort_keys=True, default=float)
        stream.flush()
        os.fsync(stream.fileno())
    os.replace(tmp, path)


def simulate(scene: dict, case_dir: Path, checkpoint: bool = False, restart=None) -> dict:
    """Run a resolved scene; returns {'metrics', 'timings', 'info'} or raises SimulationFailed."""
    if scene["kind"] == "rcc":
        if checkpoint or restart:
            raise InputError("--checkpoint/--restart: an rcc case has no steps to share")
        from femcontact import rcc

        return rcc.run_case(scene, case_dir)
    from femcontact import simulation

    return simulation.run_scene(scene, case_dir, checkpoint, restart)


def command(args) -> int:
    from mpi4py import MPI

    scene = load_scene(args.scene, args.set)
    rank = MPI.COMM_WORLD.rank
    case_dir = Path(args.out or Path("results", "run", case_id(scene)))
    if rank == 0:
        case_dir.mkdir(parents=True, exist_ok=True)
        write_json_atomic(case_dir / "scene.json", scene)
    MPI.COMM_WORLD.barrier()
    start = time.perf_counter()
    try:
        result = {"status": "ok", "reason": None, **simulate(scene, case_dir, args.checkpoint, args.restart)}
    except Exception as error:  # recorded, never a half-written result
        reason = f"{type(error).__name__}: {error}"
        result = {"status": "failed", "reason": reason, "metrics": {}, "timings": {},
                  "info": {"traceback": traceback.format_exc()}}
        print(f"femcontact run: case failed: {reason}", file=sys.stderr)
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
