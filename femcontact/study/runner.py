"""`femcontact study STUDY.toml`: run the cases of a study (study_file.py) not done yet.

A case is done iff `results/NAME/cases/ID/result.json` exists (written atomically by
`femcontact run`, or by this runner for a case that timed out or crashed without one), so
running a study again resumes it. Cases run as subprocesses through the study's launcher
(`mpirun -n {ranks}` by default, `srun -n {ranks}` under SLURM), `jobs` at a time; one-rank
cases under the default launcher run in warm worker processes instead, one per job slot, each
paying the start-up once (workers.py). Each job slot has its own FFCx JIT cache
(`XDG_CACHE_HOME`), held with a file lock for the runner's lifetime, so concurrent first
compilations never contend for the same cache, even between two studies run at once. Every
case records the software that ran it (`provenance`). See docs/studies.md.
"""
import ctypes
import fcntl
import functools
import itertools
import json
import os
import select
import shlex
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from femcontact.errors import InputError
from femcontact.io import (WriteError, describe, make_dir, read_result, remove_stale_compilations, write_json_atomic,
                           write_text_atomic)
from femcontact.study.study_file import SCHEMA, Case, Study, to_toml
from femcontact.study.workers import Pool, Worker


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
                    signal_group(job.process, signal.SIGTERM)
                elif job.killed and elapsed > limit + 5:
                    signal_group(job.process, signal.SIGKILL)
                continue
            self.running.remove(job)
            result = read_result(job.case.dir) if not job.killed else None
            if result is None:  # killed, crashed or exited without a result: the runner records why
                reason = job.killed or exit_reason(code, job.case.dir / "log.txt")
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
            signal_group(job.process, signal.SIGTERM)
        deadline = time.monotonic() + 5
        for job in self.running:
            try:
                job.process.wait(max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                signal_group(job.process, signal.SIGKILL)
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


def signal_group(process: subprocess.Popen, sig: int) -> None:
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


def exit_reason(code: int, log: Path) -> str:
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
