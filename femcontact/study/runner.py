"""`femcontact study STUDY.toml`: expand a sweep into cases and run the ones not done yet.

A study file names a base scene, inline overrides and a sweep (a grid, zipped
lists and explicit cases, over dotted scene keys such as `steps.1.force`). Every
case is resolved and validated before anything runs; its id is the hash of its
resolved scene (`femcontact.scene.case_id`), so re-running a study finds its
finished cases again: a case is done iff `results/NAME/cases/ID/result.json`
exists (written atomically by `femcontact run`, or by this runner for a case
that timed out or crashed without one).

Cases run as subprocesses through the study's launcher (`mpirun -n {ranks}` by
default, `srun -n {ranks}` under SLURM), `jobs` at a time; one-rank cases under the
default launcher run in warm worker processes instead, one per job slot, each paying
the start-up once (workers.py). Each job slot has its own FFCx JIT cache
(`XDG_CACHE_HOME`), held with a file lock for the runner's lifetime, so concurrent first
compilations never contend for the same cache, even between two studies run at once.
See docs/studies.md.
"""
import ctypes
import fcntl
import functools
import itertools
import json
import math
import os
import re
import select
import shlex
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator

from femcontact.outputs.result import STATUSES
from femcontact.errors import InputError
from femcontact.io import (WriteError, describe, make_dir, read_result, remove_stale_compilations, write_json_atomic,
                           write_text_atomic)
from femcontact.config.schema import Field, TableList, set_key, validate
from femcontact.config.scene import apply_overrides, case_id, read_toml
from femcontact.families import plot_kinds, resolve_scene
from femcontact.study.workers import Pool, Worker

_TABLE = Field("any", {}, "a table", check=lambda v: None if isinstance(v, dict) else "must be a table")
_TABLES = Field("any", [], "an array of tables",
                check=lambda v: None if isinstance(v, list) and all(isinstance(t, dict) for t in v)
                else "must be an array of tables")

SCHEMA = {
    "study": {
        "name": Field("str", doc="study name: results go to results/NAME/",
                      check=lambda v: None if v and "/" not in v and not v.startswith(".") else "not a plain name"),
        "description": Field("str", "", "what the study is for"),
        "scene": Field("str", doc="base scene file, relative to the study file"),
        "jobs": Field("int", 0, "cases run at once; 0 = cores // ranks_per_case", min=0),
        "ranks_per_case": Field("int", 1, "MPI ranks per case", min=1),
        "time_limit": Field("float", 600.0, "seconds per case; a case past it is killed and recorded failed",
                            positive=True),
        "launcher": Field("str", "mpirun -n {ranks}", "command prefix that starts an MPI job of {ranks} ranks",
                          check=lambda v: _check_launcher(v)),
        "shared_steps": Field("int", 0, "> 0: cases agreeing on their first steps compute them once", min=0),
        "workers": Field("bool", True, "one-rank cases under the default launcher run in warm worker processes "
                         "(one per job, importing femcontact once); false: a fresh launcher process per case"),
    },
    "scene": _TABLE,
    "sweep": {
        "grid": Field("any", {}, "key = [values]: every combination", check=lambda v: _check_lists(v, False)),
        "zip": Field("any", {}, "key = [values]: lists of one length, taken together",
                     check=lambda v: _check_lists(v, True)),
        "cases": _TABLES,
    },
    "plot": TableList({
        "x": Field("str", doc="column on the x axis (a swept or scene key, a metric, time.PHASE)"),
        "y": Field("str", doc="column on the y axis"),
        "series": Field("str", "", "column whose values make separate curves"),
        "kind": Field("str", "line", "line, scatter, or a study family's plot kind (femcontact.families): "
                      + ", ".join(plot_kinds()), choices=("line", "scatter", *plot_kinds())),
        "select": Field("any", {}, "force_curves, sweep: only cases whose scene has key = value (or one of a list)",
                        check=lambda v: None if isinstance(v, dict) else "must be a table"),
        "logx": Field("bool", False, "logarithmic x axis"),
        "logy": Field("bool", False, "logarithmic y axis"),
        "title": Field("str", "", "plot title"),
        "file": Field("str", "", "PNG file name in results/NAME/ (default Y_vs_X.png)"),
    }, "plots written by `femcontact report`", default=[]),
    "snapshots": {
        "select": _TABLES,
        "field": Field("str", "von_mises", "field shown", choices=("von_mises",)),
        "zoom": Field("any", "", "named point of the fields file, or [x, y(, z), radius]",
                      check=lambda v: None if isinstance(v, str) or (
                          isinstance(v, list) and len(v) in (3, 4) and all(isinstance(x, (int, float)) for x in v))
                      else "expected a name or [x, y(, z), radius]"),
        "zoom_radius": Field("float", 0.0, "zoom radius around a named point; 0 = 1/8 of the model size", min=0.0),
        "scale": Field("float", 1.0, "displacement magnification", min=0.0),
    },
    "animation": {
        "select": Field("any", [], "cases filmed in the report (femcontact animate), as [snapshots] selects them; "
                        "they run with outputs.fields = true",
                        check=lambda v: None if isinstance(v, list) and all(isinstance(t, dict) and t for t in v)
                        else "must be an array of non-empty tables"),
        "scale": Field("float", 1.0, "displacement magnification of the films", min=0.0),
        "every": Field("int", 1, "film every N-th increment (outputs.every of the filmed cases)", min=1),
    },
    "report": {
        "columns": Field("strs", [], "headline columns of summary.md and index.html (at most MAX_COLUMNS; "
                         "default: swept keys, status, the family's primary metrics, wall time)",
                         check=lambda v: _check_columns(v)),
    },
}
MAX_COLUMNS = 25  # a wider table is not readable; every column stays in results.csv


def _check_columns(columns: list[str]) -> str | None:
    bad = [c for c in columns if not c.strip()] or [c for i, c in enumerate(columns) if c in columns[:i]]
    if bad:
        return f"column {bad[0]!r} is empty or repeated"
    if len(columns) > MAX_COLUMNS:
        return f"{len(columns)} columns, at most {MAX_COLUMNS} (the rest is in results.csv)"
    return None


def flatten(table: dict, prefix: str = "") -> dict:
    """{'peg': {'width': 1}} -> {'peg.width': 1} (TOML turns unquoted dotted keys into sub-tables)."""
    flat = {}
    for key, value in table.items():
        if isinstance(value, dict):
            flat.update(flatten(value, f"{prefix}{key}."))
        else:
            flat[prefix + key] = value
    return flat


def _check_lists(table, same_length: bool) -> str | None:
    if not isinstance(table, dict):
        return "must be a table of key = [values]"
    lists = flatten(table)
    bad = [key for key, values in lists.items() if not isinstance(values, list) or not values]
    if bad:
        return f"{bad[0]} must be a non-empty list of values"
    if same_length and len({len(values) for values in lists.values()}) > 1:
        return "zipped lists must have one length: " + ", ".join(f"{k} has {len(v)}" for k, v in lists.items())
    return None


def _check_launcher(launcher: str) -> str | None:
    """A complaint about a launcher command, or None: it must format with {ranks} alone and name a program."""
    import shutil

    try:
        words = shlex.split(launcher.format(ranks=1))
    except (KeyError, IndexError, ValueError) as error:
        return f"cannot be read ({type(error).__name__}: {error}); the only placeholder is {{ranks}}"
    if words and shutil.which(words[0]) is None:
        return f"{words[0]!r}: no such program"
    return None


@dataclass
class Case:
    """One case of a study: its swept parameters, resolved scene and directory."""
    params: dict
    scene: dict
    id: str
    dir: Path
    prefix: "Case | None" = None  # the shared-prefix computation it restarts from

    @property
    def is_prefix(self) -> bool:
        """A shared prefix (results/NAME/prefix/ID), not a case of the study."""
        return self.dir.parent.name == "prefix"


@dataclass
class Study:
    """A loaded study: settings, cases (in sweep order), swept keys and result paths."""
    path: Path
    settings: dict
    cases: list[Case]
    keys: list[str]
    results: Path
    plots: list = field(default_factory=list)
    snapshots: dict = field(default_factory=dict)
    report: dict = field(default_factory=dict)
    base: dict = field(default_factory=dict)  # the base scene with the study's and --set values, unresolved
    sweep: dict = field(default_factory=dict)
    count: int = 0  # parameter sets of the sweep (cases before duplicates are merged)
    animation: dict = field(default_factory=dict)

    @property
    def database(self) -> Path:
        return self.results / "results.sqlite"


def get_key(scene: dict, dotted: str):
    """scene['a'][1]['b'] for 'a.1.b'; None when absent."""
    node = scene
    for part in dotted.split("."):
        if isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]
        elif isinstance(node, dict) and part in node:
            node = node[part]
        else:
            return None
    return node


def expand(sweep: dict) -> Iterator[dict]:
    """Parameter sets of a sweep, one at a time: grid (product) x zip (together), then the
    explicit cases. An empty sweep is the base scene alone."""
    grid, zipped = flatten(sweep.get("grid", {})), flatten(sweep.get("zip", {}))
    explicit = [flatten(case) for case in sweep.get("cases", [])]
    if not grid and not zipped:
        yield from explicit or [{}]
        return
    zip_sets = [dict(zip(zipped, values)) for values in zip(*zipped.values())] or [{}]
    for values in itertools.product(*grid.values()):
        for z in zip_sets:
            yield {**dict(zip(grid, values)), **z}
    yield from explicit


def count_cases(sweep: dict) -> int:
    """How many parameter sets `expand(sweep)` yields, without making them."""
    grid, zipped = flatten(sweep.get("grid", {})), flatten(sweep.get("zip", {}))
    explicit = len(sweep.get("cases", []))
    if not grid and not zipped:
        return explicit or 1
    return math.prod(len(values) for values in grid.values()) * \
        (len(next(iter(zipped.values()))) if zipped else 1) + explicit


def swept_keys(sweep: dict) -> list[str]:
    """The dotted scene keys a sweep sets, in the order of its parameter sets."""
    explicit = [key for case in sweep.get("cases", []) for key in flatten(case)]
    return list(dict.fromkeys([*flatten(sweep.get("grid", {})), *flatten(sweep.get("zip", {})), *explicit]))


def load_study(path, overrides=(), results_root="results", max_cases=None, resolve_cases=True) -> Study:
    """Read and validate a study file and resolve every case; raises InputError naming bad cases.

    A sweep of more than `max_cases` cases (None: no limit) is refused before any is made. With
    `resolve_cases` false the cases are left to `iter_cases` (one at a time, e.g. for --list)."""
    path = Path(path)
    try:
        raw = validate(read_toml(path), SCHEMA)
    except InputError as error:
        raise InputError(f"{path}: {error}") from None
    settings = raw["study"]
    base = read_toml(path.parent / settings["scene"])
    for key, value in flatten(raw["scene"]).items():
        set_key(base, key, value)
    apply_overrides(base, overrides)  # --set changes the base scene; the sweep still varies its own keys
    count = count_cases(raw["sweep"])
    if max_cases is not None and count > max_cases:
        raise InputError(f"{path}: the sweep makes {count} cases, more than the limit of {max_cases}; nothing was "
                         f"run (pass --max-cases {count} to run them all, or --list to see them)")
    results = Path(results_root) / settings["name"]
    study = Study(path, settings, [], swept_keys(raw["sweep"]), results, raw["plot"], raw["snapshots"],
                  raw["report"], base=base, sweep=raw["sweep"], count=count, animation=raw["animation"])
    _check_scene_once(study)
    if resolve_cases:
        make_cases(study)
    return study


def make_cases(study: Study) -> None:
    """Resolve every case of the study into `study.cases`, with their shared prefixes."""
    study.cases = list(iter_cases(study))
    if study.settings["shared_steps"]:
        attach_prefixes(study.cases, study.settings["shared_steps"], study.results)


def _check_scene_once(study: Study) -> None:
    """Refuse in one line a base scene that is invalid whatever the sweep sets: its error names
    no swept key and the first case fails with the same error."""
    try:
        resolve_scene(study.base)
        return
    except InputError as error:
        message = str(error)
    forms = {form for key in study.keys for form in (key, re.sub(r"\.(\d+)", r"[\1]", key))}
    if any(form in message for form in forms):
        return  # the sweep may mend it; each case says
    try:
        resolve_scene(_case_data(study.base, next(expand(study.sweep))))
    except InputError as error:
        if str(error) == message:
            raise InputError(f"{study.path}: {study.count} invalid case(s), nothing was run: {message} (the scene "
                             f"{study.settings['scene']} with the study's values, whatever the sweep sets)") from None


def _case_data(base: dict, params: dict) -> dict:
    data = json.loads(json.dumps(base))
    for key, value in params.items():
        set_key(data, key, value)
    return data


def iter_cases(study: Study) -> Iterator[Case]:
    """The study's distinct cases in sweep order, resolved one at a time; once all are made,
    raises InputError listing the invalid ones, grouped by error."""
    problems, seen = {}, set()
    for params in expand(study.sweep):
        try:
            scene = resolve_scene(_case_data(study.base, params))
            if "outputs" in scene and any(matches(scene, flatten(t)) for t in study.animation["select"]):
                scene["outputs"].update(fields=True, every=study.animation["every"])  # filmed in the report
        except InputError as error:
            problems.setdefault(str(error), []).append(params)
            continue
        identity = case_id(scene)
        if identity not in seen:
            seen.add(identity)
            yield Case({key: get_key(scene, key) for key in study.keys}, scene, identity,
                       study.results / "cases" / identity)
    if problems:
        invalid = sum(map(len, problems.values()))
        lines = [f"case {_describe(cases[0])}: {message}" if len(cases) == 1 else
                 f"{message} ({'every case' if len(cases) == study.count else f'{len(cases)} cases'}: "
                 + "; ".join(_describe(params) for params in cases[:3]) + ("; ..." if len(cases) > 3 else "") + ")"
                 for message, cases in problems.items()]
        raise InputError(f"{study.path}: {invalid} invalid case(s), nothing was run:\n  " + "\n  ".join(lines))


def matches(scene: dict, selector: dict) -> bool:
    """Does the scene have every dotted key of `selector` at its value (numbers to 1e-9)?"""
    def same(a, b):
        if isinstance(a, (int, float)) and isinstance(b, (int, float)):
            return math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-12)
        return a == b

    return all(same(get_key(scene, key), value) for key, value in selector.items())


def attach_prefixes(cases: list[Case], shared: int, results: Path) -> None:
    """Give every case with more than `shared` steps the prefix case it restarts from."""
    prefixes = {}
    for case in cases:
        if len(case.scene["steps"]) <= shared:
            continue
        scene = {**case.scene, "steps": case.scene["steps"][:shared]}
        scene.pop("dislodging", None)  # read only after the shared steps
        if "outputs" in scene:  # a filmed case shares its prefix with the others: the prefix writes no time series
            scene["outputs"] = {**scene["outputs"], "fields": False, "every": 1}
        identity = case_id(scene)
        if identity not in prefixes:
            prefixes[identity] = Case({}, scene, identity, results / "prefix" / identity)
        case.prefix = prefixes[identity]


def _describe(params: dict) -> str:
    return ", ".join(f"{key}={value!r}" for key, value in params.items()) or "(base scene)"


# -- the case directory ---------------------------------------------------------------------------

def status_counts(results) -> dict:
    """{status: number of results} over STATUSES (results without a result file are not counted)."""
    counts = dict.fromkeys(STATUSES, 0)
    for result in results:
        if result is not None:
            counts[result["status"] if result["status"] in counts else "failed"] += 1
    return counts


def to_toml(scene: dict) -> str:
    """TOML text of a resolved scene: scalars, then [tables], then [[arrays of tables]]."""
    lines = [f"{_key(k)} = {_value(v)}" for k, v in scene.items() if not _is_table(v) and not _is_tables(v)]
    for key, value in scene.items():
        if _is_table(value):
            lines += ["", f"[{_key(key)}]"] + _table_lines(value)
    for key, value in scene.items():
        if _is_tables(value):
            for item in value:
                lines += ["", f"[[{_key(key)}]]"] + _table_lines(item)
    return "\n".join(lines) + "\n"


def _is_table(value) -> bool:
    return isinstance(value, dict) and bool(value)


def _is_tables(value) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(v, dict) for v in value)


def _table_lines(table: dict, prefix: str = "") -> list[str]:
    lines = []
    for key, value in table.items():
        if _is_table(value):
            lines += _table_lines(value, f"{prefix}{_key(key)}.")
        else:
            lines.append(f"{prefix}{_key(key)} = {_value(value)}")
    return lines


def _key(key: str) -> str:
    return key if key and all(c.isalnum() or c in "_-" for c in key) else json.dumps(key)


def _value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(map(_value, value)) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_key(k)} = {_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"cannot write {value!r} as TOML")


def provenance() -> dict:
    """Software versions and git commit of the code that runs the cases (recorded per case)."""
    from importlib import metadata

    versions = {"python": sys.version.split()[0]}
    for name, dist in (("dolfinx", "fenics-dolfinx"), ("petsc4py", "petsc4py"), ("numpy", "numpy"),
                       ("mpi4py", "mpi4py")):
        try:
            versions[name] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            versions[name] = None
    repo = Path(__file__).resolve().parent.parent
    git = subprocess.run(["git", "-C", str(repo), "describe", "--always", "--dirty", "--abbrev=40"],
                         capture_output=True, text=True)
    versions["git_commit"] = git.stdout.strip() if git.returncode == 0 else None
    return versions


# -- running --------------------------------------------------------------------------------------

@dataclass
class Job:
    """A running case (or shared prefix) and its job slot."""
    case: Case
    process: subprocess.Popen
    slot: int
    started: float
    killed: str | None = None
    worker: Worker | None = None  # the warm worker running it, if any (then `process` is the worker's)

    def exit_code(self) -> int | None:
        """The case's exit code once it is over, else None."""
        return self.worker.poll() if self.worker else self.process.poll()


def _die_with_parent(parent: int) -> None:
    """In the child: get SIGTERM when the runner dies, even by SIGKILL (Linux prctl PR_SET_PDEATHSIG)."""
    ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM)
    if os.getppid() != parent:
        os._exit(1)


def femcontact_command() -> list[str]:
    """The `femcontact` executable of this environment."""
    script = Path(sys.executable).parent / "femcontact"
    return [str(script)] if script.exists() else [sys.executable, "-m", "femcontact"]


def take_slot(cache_root: Path, kind: str = "slot"):
    """The first JIT cache slot `KIND-K` that no other runner or SLURM task on this file system
    holds: (its name, the open lock file, held until closed or the process ends)."""
    cache_root.mkdir(parents=True, exist_ok=True)
    for number in itertools.count():
        lock = open(cache_root / f"{kind}-{number}.lock", "w")
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return f"{kind}-{number}", lock
        except BlockingIOError:
            lock.close()


def remove_unfinished_compilations(cache_root: Path, slot: str) -> None:
    """Clean a held job slot's JIT cache (see femcontact.io.remove_stale_compilations). Safe at
    any age: the slot's lock makes its cache this process's own."""
    remove_stale_compilations(cache_root / slot / "fenics", older_than=0.0)


def case_command(case: Case, launcher: str, ranks: int) -> list[str]:
    """The command that runs `case` in its directory: LAUNCHER FEMCONTACT run scene.toml ..."""
    return shlex.split(launcher.format(ranks=ranks)) + femcontact_command() + run_arguments(case)


def run_arguments(case: Case) -> list[str]:
    """The `femcontact` arguments that run `case` in its directory: run scene.toml --out . ..."""
    arguments = ["run", "scene.toml", "--out", "."]
    if case.prefix is not None:
        arguments += ["--restart", str((case.prefix.dir / "checkpoint").resolve())]
    elif case.is_prefix:
        arguments += ["--checkpoint"]
    return arguments


class Runner:
    """Runs cases `jobs` at a time, enforcing the time limit and recording each result."""

    def __init__(self, study: Study, jobs: int, ranks: int, database, progress):
        self.study, self.jobs, self.ranks = study, jobs, ranks
        self.database, self.progress = database, progress
        self.provenance = provenance()
        cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
        self.cache_root = cache / "femcontact-jit"
        self.running: list[Job] = []
        self.slots = [take_slot(self.cache_root) for _ in range(jobs)]  # (name, lock) per job slot
        for name, _ in self.slots:
            remove_unfinished_compilations(self.cache_root, name)
        settings = study.settings
        warm = settings["workers"] and ranks == 1 and settings["launcher"] == SCHEMA["study"]["launcher"].default
        self.pool = Pool(self.environment, functools.partial(_die_with_parent, os.getpid())) if warm else None

    def environment(self, slot: int) -> dict:
        """The environment of job slot `slot`'s processes: its own JIT cache."""
        return launch_environment(self.cache_root / self.slots[slot][0])

    def command(self, case: Case) -> list[str]:
        if self.pool is not None:  # what the worker runs, as a fresh process would
            return femcontact_command() + run_arguments(case)
        return case_command(case, self.study.settings["launcher"], self.ranks)

    def start(self, case: Case, slot: int) -> None:
        make_dir(case.dir)
        command = self.command(case)
        worker = self.pool.worker(slot) if self.pool is not None else None
        try:
            (case.dir / "result.json").unlink(missing_ok=True)
            # bookkeeping of a case not done yet: a rerun writes it again, so no fsync
            write_text_atomic(case.dir / "scene.toml", to_toml(case.scene), sync=False)
            write_json_atomic(case.dir / "runner.json", {**self.provenance, "command": command, "ranks": self.ranks,
                                                         "slot": slot, "worker": worker and worker.pid,
                                                         "started": time.time()}, sync=False)
            log = open(case.dir / "log.txt", "wb")
        except OSError as error:
            raise WriteError(describe(error, case.dir)) from None
        if worker is not None:  # the worker appends to the log just emptied
            log.close()
            worker.submit(case.dir.resolve(), run_arguments(case))
            self.running.append(Job(case, worker.process, slot, time.monotonic(), worker=worker))
            return
        with log:
            try:
                process = subprocess.Popen(command, cwd=case.dir, stdout=log, stderr=subprocess.STDOUT,
                                           env=self.environment(slot),
                                           stdin=subprocess.DEVNULL, start_new_session=True,
                                           preexec_fn=functools.partial(_die_with_parent, os.getpid()))
            except OSError as error:
                raise InputError(f"study.launcher: cannot start {command[0]!r} ({error.strerror})") from None
        self.running.append(Job(case, process, slot, time.monotonic()))

    def poll(self) -> list[tuple[Case, dict]]:
        """Reap finished jobs (killing those past the time limit); returns (case, result) pairs."""
        finished, limit = [], self.study.settings["time_limit"]
        for job in list(self.running):
            elapsed = time.monotonic() - job.started
            code = job.exit_code()
            if code is None:
                if elapsed > limit and not job.killed:
                    job.killed = f"time limit of {limit:g} s exceeded"
                    _signal_group(job.process, signal.SIGTERM)
                elif job.killed and elapsed > limit + 5:
                    _signal_group(job.process, signal.SIGKILL)
                continue
            self.running.remove(job)
            result = read_result(job.case.dir) if not job.killed else None
            if result is None:  # killed, crashed or exited without a result: the runner records why
                reason = job.killed or _exit_reason(code, job.case.dir / "log.txt")
                result = {"status": "failed", "reason": reason, "metrics": {}, "timings": {},
                          "info": {"ranks": self.ranks}}
                write_json_atomic(job.case.dir / "result.json", result)
            runner = json.loads((job.case.dir / "runner.json").read_text())
            write_json_atomic(job.case.dir / "runner.json", {**runner, "wall": elapsed})
            finished.append((job.case, result))
        return finished

    def stop_all(self) -> None:
        """Terminate every running job (their results stay missing, so they rerun next time)."""
        for job in self.running:
            _signal_group(job.process, signal.SIGTERM)
        deadline = time.monotonic() + 5
        for job in self.running:
            try:
                job.process.wait(max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                _signal_group(job.process, signal.SIGKILL)
                job.process.wait()
        self.running.clear()
        self.close_workers()

    def close_workers(self) -> None:
        if self.pool is not None:
            self.pool.close()

    def run(self, cases: list[Case], prefixes: list[Case]) -> None:
        """Run the prefixes and cases; a case whose prefix failed is recorded failed without running."""
        pending = prefixes + cases
        running_prefixes = {prefix.id for prefix in prefixes}
        prefix_results = {case.prefix.id: read_result(case.prefix.dir) for case in cases
                          if case.prefix is not None and case.prefix.id not in running_prefixes}
        while pending or self.running:
            free = sorted(set(range(self.jobs)) - {job.slot for job in self.running})
            for case in list(pending):
                if not free:
                    break
                if case.prefix is not None and case.prefix.id not in prefix_results:
                    continue  # waits for its prefix
                pending.remove(case)
                prefix = prefix_results.get(case.prefix.id) if case.prefix else None
                if prefix is not None and prefix["status"] != "ok":
                    result = prefix_outcome(case.prefix.id, prefix)
                    make_dir(case.dir)
                    write_text_atomic(case.dir / "scene.toml", to_toml(case.scene))
                    write_json_atomic(case.dir / "runner.json", self.provenance)
                    write_json_atomic(case.dir / "result.json", result)
                    self._finish(case, result)
                    continue
                self.start(case, free.pop(0))
                self.progress.update(self.running)
            for case, result in self.poll():
                if case.is_prefix:
                    prefix_results[case.id] = result
                    self.progress.finished(case, result, prefix=True)
                else:
                    self._finish(case, result)
            self.progress.update(self.running)
            self.wait(0.02)
        self.close_workers()

    def wait(self, timeout: float) -> None:
        """Sleep `timeout` s, or less if every running job is a worker's and one replies (or dies);
        not at all when nothing runs (a slot is free for the next case)."""
        if not self.running:
            return
        pipes = [job.worker.process.stdout for job in self.running if job.worker is not None]
        if pipes and len(pipes) == len(self.running):
            select.select(pipes, [], [], timeout)
        else:
            time.sleep(timeout)

    def _finish(self, case: Case, result: dict) -> None:
        self.database.record(case)
        self.progress.finished(case, result)


def prefix_outcome(prefix_id: str, prefix: dict) -> dict:
    """The result of a case whose shared prefix did not end ok: without equilibrium as its prefix
    (the later steps are never reached), or failed."""
    if prefix["status"] == "no_equilibrium":
        return {"status": "no_equilibrium", "reason": f"shared prefix {prefix_id}: {prefix['reason']}",
                "metrics": prefix.get("metrics", {}), "timings": {}, "info": {}}
    return {"status": "failed", "reason": f"shared prefix {prefix_id} failed: {prefix['reason']}",
            "metrics": {}, "timings": {}, "info": {}}


def _signal_group(process: subprocess.Popen, sig: int) -> None:
    try:
        os.killpg(process.pid, sig)
    except ProcessLookupError:
        pass


def launch_environment(cache: Path) -> dict:
    """Environment of a case's launch: its own JIT cache, unbuffered output, one thread per rank,
    and what Open MPI needs to start at all, as the Makefile sets it: run as root (containers)
    and more ranks than cores. Values already set are kept."""
    env = {**os.environ, "XDG_CACHE_HOME": str(cache), "PYTHONUNBUFFERED": "1"}
    for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        env.setdefault(name, "1")
    env.setdefault("OMPI_MCA_rmaps_base_oversubscribe", "1")
    if os.geteuid() == 0:
        env.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
        env.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    return env


def _is_rule(line: str) -> bool:
    """A banner line of dashes, equals signs or stars (Open MPI frames its messages in them)."""
    return len(line) >= 3 and not line.strip("-=*")


def _exit_reason(code: int, log: Path) -> str:
    """Why a case ended without a result: the exit status and the log's own error, i.e. its last
    line, or for a message framed in banner lines (an MPI launcher's) the framed text."""
    how = f"killed by signal {-code}" if code < 0 else f"exited with code {code}"
    lines = [line.strip() for line in log.read_text(errors="replace").splitlines() if line.strip()] \
        if log.exists() else []
    while lines and _is_rule(lines[-1]):
        lines.pop()
        framed = []
        while lines and not _is_rule(lines[-1]):
            framed.insert(0, lines.pop())
        if framed:
            return f"{how} without a result; launcher: {' '.join(framed)[:300]}"
    return f"{how} without a result" + (f"; last log line: {lines[-1][:300]}" if lines else "")


# -- progress -------------------------------------------------------------------------------------

class Progress:
    """On a terminal a progress bar (and a line per failure), otherwise a line per finished case;
    nothing with --quiet."""

    def __init__(self, total: int, quiet: bool, stream=sys.stderr):
        self.total, self.quiet, self.stream = total, quiet, stream
        self.bar = not quiet and stream.isatty()
        self.done = self.failed = 0
        self.start = time.monotonic()
        self.drawn = 0.0

    def finished(self, case: Case, result: dict, prefix: bool = False) -> None:
        if not prefix:
            self.done += 1
            self.failed += result["status"] == "failed"
        if self.quiet or (self.bar and result["status"] == "ok"):
            return
        what = f"prefix {case.id}" if prefix else f"{case.id} {_describe(case.params)}"
        line = f"[{self.done}/{self.total}] {result['status']:6s} {what}"
        if result["status"] != "ok":
            line += f": {result['reason']}"
        self._clear()
        print(line, file=self.stream, flush=True)
        self.drawn = 0.0

    def update(self, running: list[Job]) -> None:
        now = time.monotonic()
        if not self.bar or now - self.drawn < 0.2:
            return
        self.drawn = now
        elapsed = now - self.start
        eta = f"{_duration(elapsed / self.done * (self.total - self.done))}" if self.done else "?"
        filled = int(30 * self.done / max(self.total, 1))
        self.stream.write(f"\r[{'#' * filled}{'.' * (30 - filled)}] {self.done}/{self.total} done, "
                          f"{self.failed} failed, {len(running)} running, {_duration(elapsed)} elapsed, "
                          f"ETA {eta}\x1b[K")
        self.stream.flush()

    def close(self) -> None:
        """Leave the terminal's last line free for the summary."""
        self._clear()

    def _clear(self) -> None:
        if self.bar:
            self.stream.write("\r\x1b[K")
            self.stream.flush()


def _duration(seconds: float) -> str:
    seconds = int(seconds)
    return f"{seconds // 3600}h{seconds % 3600 // 60:02d}m" if seconds >= 3600 else \
        f"{seconds // 60}m{seconds % 60:02d}s" if seconds >= 60 else f"{seconds}s"
