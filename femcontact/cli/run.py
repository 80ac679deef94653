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
from femcontact import api
from femcontact.errors import InputError
from femcontact.outputs.result import ANSWERS


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
    scene = api.load_scene(args.scene, args.set)  # bad input is refused before MPI starts
    try:
        result = api.run(scene, out=args.out, quiet=args.quiet, checkpoint=args.checkpoint, restart=args.restart)
    except InputError as error:
        raise InputError(f"{args.scene}: {error}") from None
    from mpi4py import MPI

    if MPI.COMM_WORLD.rank == 0 and not args.quiet:
        print_summary(result)
    return 0 if result.status in ANSWERS else 1


def print_summary(result: api.Result) -> None:
    print(f"case {result.case_dir}: {result.status}" + (f" ({result.reason})" if result.reason else ""))
    for key, value in sorted(result.metrics.items()):
        if isinstance(value, (int, float, bool, str)):
            print(f"  {key:32s} {value:.6g}" if isinstance(value, float) else f"  {key:32s} {value}")
    print(f"  {'wall time (s)':32s} {result.timings['total']:.3g}")
