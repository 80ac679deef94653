"""`femcontact hertz`: a Hertz benchmark at one contact-zone size, for timing against other codes.

    femcontact hertz [--dim 2|3] --contact-size H [--degree 1|2] [--ranks N] [--json]

--dim 2 (the default): a rigid cylinder on a plane-strain block (docs/references.md); --dim 3: a
rigid sphere (R 50 mm, P 2000 N) on a block, its quarter meshed with symmetry planes.
Prints the dofs, Newton iterations, simulated a (mm) and p0 (MPa), the wall time per phase
(s, the whole process included) and, with --json, one JSON object whose `surface` lists
[x (mm), p (MPa)] for every node of the loaded top edge (2-D), [r (mm), p (MPa)] with
r = sqrt(x^2 + y^2) for every node of the loaded top face (3-D), p = 0 outside contact: the
vertices with --degree 1 (pressures lumped to them), the vertices and edge midpoints with
--degree 2 (pressures recovered at each node: `Recorder.recovered_pressure`). With
--ranks N > 1 the command starts itself under `mpirun -n N` (or the launcher in the
environment variable FEMCONTACT_LAUNCHER, e.g. "srun -n {ranks}").
"""
import json
import math
import os
import shlex
import subprocess
import sys
import time

from femcontact.process import start_mpi_for_meshing
from femcontact.errors import InputError


def _process_age() -> float:
    """Seconds since this process started (Linux /proc; elsewhere since this module's import)."""
    try:
        with open("/proc/self/stat") as stat, open("/proc/uptime") as uptime:
            started = int(stat.read().rsplit(")", 1)[1].split()[19]) / os.sysconf("SC_CLK_TCK")
            return float(uptime.read().split()[0]) - started
    except (OSError, ValueError, IndexError):
        return 0.0


START = time.perf_counter() - _process_age()


def add_arguments(parser) -> None:
    parser.add_argument("--dim", type=int, default=2, choices=(2, 3),
                        help="2: cylinder on a plane-strain block; 3: sphere on a block (quarter model)")
    parser.add_argument("--contact-size", type=float, required=True,
                        help="element size in the contact zone h_c (mm); a/(k + 0.5) puts x = a mid-element")
    parser.add_argument("--degree", type=int, default=1, choices=(1, 2), help="Lagrange degree of the displacement")
    parser.add_argument("--ranks", type=int, default=1, help="MPI ranks (default 1)")
    parser.add_argument("--increments", type=int, default=2, help="load increments (default 2)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def check(args) -> None:
    if not (math.isfinite(args.contact_size) and 0 < args.contact_size <= 1.0):
        raise InputError(f"--contact-size {args.contact_size}: must be in (0, 1] mm")
    if args.ranks < 1:
        raise InputError(f"--ranks {args.ranks}: must be at least 1")
    if args.increments < 1:
        raise InputError(f"--increments {args.increments}: must be at least 1")


def relaunch(args) -> int:
    """Run this command again under mpirun with args.ranks ranks."""
    launcher = shlex.split(os.environ.get("FEMCONTACT_LAUNCHER", "mpirun -n {ranks}").format(ranks=args.ranks))
    command = [sys.executable, "-m", "femcontact", "hertz", "--dim", str(args.dim),
               "--contact-size", repr(args.contact_size),
               "--degree", str(args.degree), "--increments", str(args.increments), "--ranks", str(args.ranks)]
    return subprocess.call(launcher + command + (["--json"] if args.json else []),
                           env={**os.environ, "FEMCONTACT_HERTZ_CHILD": "1"})


def command(args) -> int:
    check(args)
    if args.ranks > 1 and not os.environ.get("FEMCONTACT_HERTZ_CHILD"):
        return relaunch(args)
    MPI = start_mpi_for_meshing()
    from femcontact.families.hertz import benchmark as hertz
    from femcontact.solver.stepping import Simulation

    comm = MPI.COMM_WORLD
    if comm.size != args.ranks:
        raise InputError(f"--ranks {args.ranks}: started on {comm.size} ranks")
    startup = time.perf_counter() - START
    scene = (hertz.scene if args.dim == 2 else hertz.scene_3d)(args.contact_size, increments=args.increments,
                                                              degree=args.degree)
    simulation = Simulation(scene, comm)
    simulation.run()
    start = time.perf_counter()
    r, p = hertz.surface_nodes(simulation)
    measured = hertz.surface_metrics(r, p)
    post = time.perf_counter() - start
    a, p0 = hertz.reference(scene)
    timings = {"startup": startup, **simulation.timings, "postprocess": post, "total": time.perf_counter() - START}
    result = {"dim": args.dim, "contact_size": args.contact_size, "degree": args.degree, "ranks": comm.size,
              "dofs": simulation.dofs,
              "newton_iterations": sum(row["newton_iterations"] for row in simulation.history),
              "newton_per_increment": [row["newton_iterations"] for row in simulation.history],
              "increments": len(simulation.history), "a": measured["a"], "p0": measured["p0"],
              "error_a": measured["a"] / a - 1, "error_p0": measured["p0"] / p0 - 1,
              "timings": timings, "surface": [[float(ri), float(pi)] for ri, pi in zip(r, p)]}
    if comm.rank != 0:
        return 0
    if args.json:
        print(json.dumps(result))
    else:
        print(f"dofs {result['dofs']}, Newton iterations {result['newton_iterations']} "
              f"in {result['increments']} increments")
        print(f"a  = {result['a']:.6f} mm   ({100 * result['error_a']:+.3f} % against {a:.6f})")
        print(f"p0 = {result['p0']:.3f} MPa  ({100 * result['error_p0']:+.3f} % against {p0:.3f})")
        print("time (s): " + ", ".join(f"{key} {value:.3f}" for key, value in timings.items()))
    return 0
