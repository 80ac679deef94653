"""femcontact from Python: load a scene, run it, run a study, read the results (docs/api.md).

    import femcontact
    scene = femcontact.load_scene("scenes/wedging_2d.toml", {"peg.insertion_depth": 6})
    result = femcontact.run(scene, out="results/run/ld6")
    result.status, result.metrics["wedged"], result.history["tilt_deg"]

    study = femcontact.Study("studies/wedging.toml")
    study.run(jobs=2)
    study.results()

`femcontact run` is `load_scene` and `run` behind a command line, `femcontact study` and
`femcontact report` are `Study.run` and `Study.report`: the same case directory, the same
`InputError` naming the bad key. Tables (`Result.history`, `Study.results()`) are pandas
DataFrames when pandas is installed, else dicts of numpy arrays (one per column).
"""
import json
import math
import shutil
import sys
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

from femcontact.errors import InputError

STALE_COMPILATION_AGE = 600.0  # s; a form compiles in well under a minute
_CLEANED_CACHES = set()  # JIT caches this process has cleaned (a study's warm worker runs many cases)


def load_scene(path, overrides=None) -> dict:
    """The resolved scene of a TOML file (every default filled in), with `overrides` applied:
    {"peg.insertion_depth": 6, "steps.0.force": [-5, 1]} or ["peg.insertion_depth=6"] as --set
    takes them. Raises InputError naming the file and the bad key or value."""
    from femcontact.families import load_scene as load

    return load(path, overrides or ())


@dataclass
class Result:
    """A finished case: `status` ("ok"; "no_equilibrium": a load that no static equilibrium carries;
    "failed"), `reason` (why it failed, or which load has no equilibrium; else None),
    `metrics` (the summary's numbers: STEP.QUANTITY at each step's end, the family's metrics),
    `timings` (s), `info` and the case directory `case_dir`."""
    status: str
    reason: str | None
    metrics: dict
    timings: dict
    info: dict
    case_dir: Path

    @classmethod
    def read(cls, case_dir) -> "Result | None":
        """The result of a case directory, or None when it has none (not run, or interrupted)."""
        try:
            data = json.loads((Path(case_dir) / "result.json").read_text())
        except (FileNotFoundError, json.JSONDecodeError):
            return None
        return cls(data["status"], data["reason"], data["metrics"], data["timings"], data["info"], Path(case_dir))

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    @property
    def history(self):
        """history.csv: one row per converged increment (columns as in the file; empty cells NaN)."""
        path = self.case_dir / "history.csv"
        if not path.exists():
            return table([])
        from femcontact.outputs.history import read_history

        return _frame(read_history(path))

    @property
    def fields(self) -> dict:
        """The field files the case wrote, by name: 'npz' (fields.npz, the final state as arrays,
        femcontact.outputs.snapshot.load reads it), 'xdmf' (fields.xdmf, the deformable body's time
        series for ParaView), 'rigid' (rigid.xdmf, the rigid body's)."""
        names = {"npz": "fields.npz", "xdmf": "fields.xdmf", "rigid": "rigid.xdmf"}
        return {key: self.case_dir / name for key, name in names.items() if (self.case_dir / name).exists()}


def table(rows: list[dict]):
    """Rows of strings (a CSV file's) as a table: numbers where every filled cell is one."""
    from femcontact.outputs.history import columns

    return _frame(columns(rows))


def _frame(columns: dict):
    """{column: array} as a pandas DataFrame when pandas is installed, else as it is."""
    try:
        import pandas
    except ImportError:
        return columns
    return pandas.DataFrame(columns)


def run(scene, out=None, quiet: bool = False, checkpoint: bool = False, restart=None) -> Result:
    """Run a scene (a resolved scene from `load_scene`, or a scene file's path) and write its case
    directory `out` (default results/run/<case id>); returns its Result, also when the simulation
    failed (status "failed", `reason` says where). `quiet`: no progress lines on standard error.
    `checkpoint`: also save the final state in OUT/checkpoint/; `restart`: start from such a
    checkpoint and run only the later steps. Bad input or an output directory that cannot be
    written raises InputError (nothing is run). Under mpirun every rank calls it."""
    from femcontact.io import WriteError, describe, make_dir, write_json_atomic
    from femcontact.process import quiet_logging, start_mpi_for_meshing
    from femcontact.config.scene import case_id

    if not isinstance(scene, dict):
        scene = load_scene(scene)
    quiet_logging()
    MPI = start_mpi_for_meshing()
    from femcontact.families.case import run_case

    comm = MPI.COMM_WORLD
    check_restart(scene, checkpoint, restart, comm.size)
    if "solver" in scene:  # the linear solver's types exist in this PETSc: asked before anything is written
        from femcontact.solver.linear import check_petsc_options

        check_petsc_options(scene["solver"]["petsc_options"])
    _clean_jit_cache(comm)
    case_dir = Path(out or Path("results", "run", case_id(scene)))
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
        result = {"status": "ok", "reason": None, **run_case(scene, case_dir, checkpoint, restart, quiet=quiet)}
    except InputError:  # found once the model is built (a history column): refused, nothing left
        if comm.rank == 0:
            _withdraw(case_dir, created)
        raise
    except Exception as error:  # recorded, never a half-written result
        from femcontact.solver.stepping import SimulationFailed

        clear = isinstance(error, (SimulationFailed, WriteError))  # their message says it all
        reason = str(error) if isinstance(error, WriteError) else f"{type(error).__name__}: {error}"
        info = {**getattr(error, "info", {})} if clear else {"traceback": traceback.format_exc()}
        timings = {**getattr(error, "timings", {})} if clear else {}
        result = {"status": "failed", "reason": reason, "metrics": {}, "timings": timings, "info": info}
        print(f"femcontact run: case failed: {reason}", file=sys.stderr)
        if "traceback" in info:
            print(info["traceback"], file=sys.stderr)
    result["timings"]["total"] = time.perf_counter() - start
    result["info"]["ranks"] = comm.size
    result["info"]["undefined_metrics"] = sorted(  # written as null: e.g. a contact centre without contact
        name for name, value in result["metrics"].items() if isinstance(value, float) and not math.isfinite(value))
    if comm.rank == 0:
        write_json_atomic(case_dir / "result.json", result)
    return Result(result["status"], result["reason"], result["metrics"], result["timings"], result["info"], case_dir)


def _withdraw(case_dir: Path, created: bool) -> None:
    """Remove what a refused run wrote: the case directory if it made it, else its files."""
    if created:
        shutil.rmtree(case_dir, ignore_errors=True)
        return
    for name in ("scene.json", "history.csv"):
        (case_dir / name).unlink(missing_ok=True)


def check_restart(scene: dict, checkpoint: bool, restart, ranks: int) -> None:
    """Refuse checkpoint/restart requests that cannot work, before anything is written."""
    if not scene.get("steps") and (checkpoint or restart):
        raise InputError(f"--checkpoint/--restart: a case of kind {scene['kind']!r} has no steps to share")
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


def jit_cache() -> Path:
    """FFCx's JIT cache directory ($XDG_CACHE_HOME/fenics, default ~/.cache/fenics)."""
    import os

    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"), "fenics")


def _clean_jit_cache(comm) -> None:
    """A compilation unfinished for 10 minutes was killed: FFCx would wait for it forever. Cleaned
    once per process: a compilation of this process's own finishes or takes the process with it."""
    from femcontact.io import remove_stale_compilations

    cache = jit_cache()
    if comm.rank == 0 and cache not in _CLEANED_CACHES:
        remove_stale_compilations(cache, older_than=STALE_COMPILATION_AGE)
        _CLEANED_CACHES.add(cache)


@dataclass
class Study:
    """A study file (docs/studies.md) loaded and every case validated (InputError names a bad one):
    `overrides` change the base scene of every case, as `femcontact study --set` does; results go to
    RESULTS/NAME/."""
    path: Path
    overrides: dict | list | None = None
    results_root: Path = Path("results")
    _study: object = field(init=False, repr=False)

    def __post_init__(self):
        from femcontact.study.study_file import load_study

        self.path, self.results_root = Path(self.path), Path(self.results_root)
        self._study = load_study(self.path, self._assignments(), self.results_root)

    def _assignments(self) -> list:
        overrides = self.overrides or ()
        return list(overrides.items()) if isinstance(overrides, dict) else list(overrides)

    @property
    def name(self) -> str:
        return self._study.settings["name"]

    @property
    def directory(self) -> Path:
        """RESULTS/NAME: the cases, results.csv, the report."""
        return self._study.results

    @property
    def cases(self) -> list[dict]:
        """Each case's id, swept parameters and directory, in sweep order."""
        return [{"case_id": case.id, **case.params, "dir": case.dir} for case in self._study.cases]

    def run(self, jobs: int | None = None, ranks_per_case: int | None = None, retry_failed: bool = False,
            force: bool = False, quiet: bool = False) -> int:
        """Run the cases not done yet (as `femcontact study`); returns 0 when every case is ok, 1
        when some failed (their reasons are in `results()`), 130 when interrupted."""
        from femcontact.study import command

        args = self._arguments(command, ["--jobs", jobs, "--ranks-per-case", ranks_per_case])
        args.retry_failed, args.force, args.quiet = retry_failed, force, quiet
        return command.command(args)

    def report(self) -> Path:
        """Write the study's plots, snapshots and summary (as `femcontact report`); returns index.html."""
        from femcontact.study import report

        report.command(self._arguments(report, []))
        return self.directory / "index.html"

    def _arguments(self, module, options: list):
        """The command line's arguments of `module` for this study, `options` ([flag, value or None, ...])."""
        import argparse

        parser = argparse.ArgumentParser()
        module.add_arguments(parser)
        argv = [str(self.path), "--results", str(self.results_root)]
        argv += [str(item) for flag, value in zip(options[::2], options[1::2]) if value is not None
                 for item in (flag, value)]
        args = parser.parse_args(argv)
        args.set = self._assignments()
        return args

    def result(self, case_id: str) -> Result | None:
        """One case's Result (None while it has none)."""
        return Result.read(self.directory / "cases" / case_id)

    def results(self):
        """One row per case: case_id, the swept keys, status, reason, then every metric (NaN where a
        case has none, e.g. not run or failed)."""
        rows = []
        for case in self._study.cases:
            result = Result.read(case.dir)
            row = {"case_id": case.id, **{key: _cell(value) for key, value in case.params.items()},
                   "status": result.status if result else "not run", "reason": result.reason if result else ""}
            if result:
                row.update({key: _cell(value) for key, value in result.metrics.items()})
            rows.append(row)
        return table(rows)


def _cell(value) -> str:
    """A value as `table` reads cells: lists as JSON text, None empty."""
    if value is None:
        return ""
    return json.dumps(value) if isinstance(value, (list, dict)) else str(value)
