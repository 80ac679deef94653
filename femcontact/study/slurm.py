"""Studies on a SLURM cluster: `femcontact study STUDY.toml --scheduler slurm`.

The cases that are not done are submitted as one job array, one array task per
case, each task an allocation of `ranks_per_case` tasks (MPI ranks) in which the
case runs as `srun -n RANKS femcontact run scene.toml --out . --quiet` (the
launcher, `--launcher`). Shared prefixes are a job array of their own, submitted
first; the case array depends on it (`afterany`). A task writes only its case
directory, exactly as a local run does (`result.json` atomically, last), so
`--status`, `femcontact report` and a resubmission read the state from the case
directories; the database is rebuilt from them, never written by a task.

Each submission is recorded in `results/NAME/slurm/`: its sbatch script, its
manifest (array index -> case) and a line of `submissions.json`. `squeue` tells
which recorded array tasks are still pending or running; those cases are never
submitted twice. See docs/slurm.md.
"""
import json
import math
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

from femcontact.errors import InputError
from femcontact.io import make_dir, read_result, write_text_atomic
from femcontact.io import write_json_atomic as _write_json
from femcontact.outputs.result import ANSWERS, STATUSES
from femcontact.study.runner import (case_command, exit_reason, prefix_outcome, provenance,
                                     remove_unfinished_compilations, signal_group, take_slot)
from femcontact.study.study_file import Case, Study, describe_params, to_toml

ACTIVE = {"PENDING", "RUNNING", "CONFIGURING", "COMPLETING", "SUSPENDED", "REQUEUED", "REQUEUE_HOLD",
          "REQUEUE_FED", "RESIZING", "SIGNALING", "STAGE_OUT"}
DEFAULT_LAUNCHER = "srun -n {ranks}"


def slurm_dir(study: Study) -> Path:
    return study.results / "slurm"


def parse_time(text: str) -> str:
    """A SLURM time limit, [D-]HH:MM:SS or MM:SS or minutes; InputError naming --time otherwise."""
    if not re.fullmatch(r"(\d+-)?\d+(:\d{1,2}){0,2}", text or ""):
        raise InputError(f"--time {text!r}: expected [D-]HH:MM:SS, MM:SS or minutes")
    return text


def default_time(time_limit: float) -> str:
    """HH:MM:SS for one array task: the study's time limit per case (s) plus 5 minutes of start-up."""
    minutes = math.ceil((time_limit + 300) / 60)
    return f"{minutes // 60:02d}:{minutes % 60:02d}:00"


def array_spec(count: int, max_concurrent: int) -> str:
    """--array value for `count` tasks, at most `max_concurrent` at once (0 = no limit)."""
    return f"0-{count - 1}" + (f"%{max_concurrent}" if max_concurrent else "")


def sbatch_script(*, name: str, kind: str, count: int, ranks: int, manifest: Path, output_dir: Path,
                  time_limit: str, partition: str = "", max_concurrent: int = 0, dependency: str = "",
                  python: str = sys.executable) -> str:
    """The sbatch script of one job array: task i runs entry i of `manifest`."""
    directives = [f"--job-name=femcontact-{name}" + ("-prefix" if kind == "prefix" else ""),
                  f"--array={array_spec(count, max_concurrent)}",
                  f"--ntasks={ranks}", "--cpus-per-task=1", f"--time={time_limit}",
                  f"--output={output_dir}/%A_%a.out"]
    if partition:
        directives.append(f"--partition={partition}")
    if dependency:
        directives.append(f"--dependency={dependency}")
    lines = ["#!/bin/bash", f"# femcontact study {name}: {count} {kind}{'es' if kind == 'prefix' else 's'}, "
             "one per array task (generated; resubmit with `femcontact study ... --scheduler slurm`)"]
    lines += [f"#SBATCH {directive}" for directive in directives]
    lines += ["export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}",
              f"exec {shlex.quote(python)} -m {__name__} task {shlex.quote(str(manifest))} "
              '"$SLURM_ARRAY_TASK_ID"']
    return "\n".join(lines) + "\n"


# -- what SLURM is doing ---------------------------------------------------------------------------

def read_submissions(study: Study) -> list[dict]:
    path = slurm_dir(study) / "submissions.json"
    return json.loads(path.read_text()) if path.exists() else []


def expand_indices(text: str) -> list[int]:
    """Array task ids of squeue's %K: '3', '0-4%2', '1,3-5' -> the indices."""
    indices = []
    for part in text.split("%")[0].strip("[]").split(","):
        low, _, high = part.partition("-")
        indices += range(int(low), int(high or low) + 1)
    return indices


def squeue_states(jobs: list[str]) -> dict[tuple[str, int], str]:
    """(array job id, task index) -> state of every pending or running task of `jobs`.

    Raises InputError when squeue is missing or fails (SLURM's state is then unknown)."""
    if not jobs:
        return {}
    if shutil.which("squeue") is None:
        raise InputError("squeue not found: cannot tell which submitted SLURM tasks are still running")
    done = subprocess.run(["squeue", "--noheader", "--array", "--format=%F|%K|%T", "--jobs=" + ",".join(jobs)],
                          capture_output=True, text=True)
    if done.returncode != 0:
        if "Invalid job id" in done.stderr:  # every recorded job has left the queue
            return {}
        raise InputError(f"squeue failed: {done.stderr.strip() or done.returncode}")
    states = {}
    for line in done.stdout.splitlines():
        job, indices, state = line.strip().split("|")
        if state in ACTIVE and indices not in ("N/A", "(null)"):
            for index in expand_indices(indices):
                states[job, index] = state
    return states


def active_tasks(study: Study) -> dict[str, dict]:
    """Case or prefix id -> {'job', 'index', 'state'} for the recorded array tasks still in SLURM."""
    submissions = read_submissions(study)
    states = squeue_states([s["job"] for s in submissions])
    active = {}
    for submission in submissions:
        for index, identity in enumerate(submission["ids"]):
            state = states.get((submission["job"], index))
            if state:
                active[identity] = {"job": submission["job"], "index": index, "state": state}
    return active


def refuse_if_in_slurm(study: Study) -> None:
    """InputError when SLURM tasks of a recorded submission are still queued or running: a local run
    must not start their cases too. Without squeue (results seen from another machine) nothing is checked."""
    if read_submissions(study) and shutil.which("squeue"):
        active = active_tasks(study)
        if active:
            jobs = sorted({task["job"] for task in active.values()})
            raise InputError(f"{study.results}: {len(active)} case(s) of this study are queued or running in "
                             f"SLURM (job {', '.join(jobs)}); wait for them or scancel them first")


# -- submission -----------------------------------------------------------------------------------

def select(study: Study, active: dict, retry_failed: bool, force: bool) -> tuple[list[Case], list[Case]]:
    """Cases to submit (no result, or failed with retry_failed, or all with force; never one still in
    SLURM) and the shared prefixes they need that are neither ok nor in SLURM."""
    cases = []
    for case in study.cases:
        result = read_result(case.dir)
        if case.id not in active and (force or result is None or (retry_failed and result["status"] == "failed")):
            cases.append(case)
    prefixes = {case.prefix.id: case.prefix for case in cases if case.prefix is not None
                and case.prefix.id not in active
                and (force or (read_result(case.prefix.dir) or {}).get("status") != "ok")}
    return cases, list(prefixes.values())


def submit(study: Study, *, ranks: int, launcher: str, time_limit: str, partition: str, max_concurrent: int,
           retry_failed: bool, force: bool, quiet: bool) -> int:
    """Submit the cases of `study` that are not done (the caller holds the study lock); prints the job ids."""
    if shutil.which("sbatch") is None:
        raise InputError("--scheduler slurm: sbatch not found (is SLURM installed and on PATH?)")
    active = active_tasks(study)
    cases, prefixes = select(study, active, retry_failed, force)
    name = study.settings["name"]
    in_slurm = sum(case.id in active for case in study.cases)
    if not quiet:
        print(f"study {name}: {len(study.cases)} cases, {in_slurm} already in SLURM, {len(cases)} to submit"
              + (f" (+{len(prefixes)} shared prefixes)" if prefixes else ""), file=sys.stderr)
    if not cases:
        return 0
    stamp = time.strftime("%Y%m%d-%H%M%S") + f"-{os.getpid()}"
    jobs = []
    dependency = sorted({active[c.prefix.id]["job"] for c in cases if c.prefix and c.prefix.id in active})
    if prefixes:
        jobs.append(_submit_array(study, "prefix", prefixes, stamp, ranks=ranks, launcher=launcher,
                                  time_limit=time_limit, partition=partition, max_concurrent=max_concurrent))
        dependency.append(jobs[-1])
    jobs.append(_submit_array(study, "case", cases, stamp, ranks=ranks, launcher=launcher, time_limit=time_limit,
                              partition=partition, max_concurrent=max_concurrent,
                              dependency="afterany:" + ":".join(dependency) if dependency else ""))
    if not quiet:
        after = f", after job {':'.join(dependency)} (shared prefixes)" if dependency else ""
        print(f"study {name}: submitted job {jobs[-1]}: {len(cases)} cases as array tasks "
              f"{array_spec(len(cases), max_concurrent)}, {ranks} rank(s) each{after}; "
              f"`femcontact study {study.path} --status` shows progress", file=sys.stderr)
    print(" ".join(jobs))
    return 0


def _submit_array(study: Study, kind: str, cases: list[Case], stamp: str, *, ranks: int, launcher: str,
                  time_limit: str, partition: str, max_concurrent: int, dependency: str = "") -> str:
    """Prepare the directories of `cases`, write manifest and script, sbatch them; returns the job id."""
    directory = (slurm_dir(study) / f"{stamp}-{kind}").resolve()
    make_dir(directory)
    tasks = []
    for case in cases:
        make_dir(case.dir)
        (case.dir / "result.json").unlink(missing_ok=True)
        write_text_atomic(case.dir / "scene.toml", to_toml(case.scene))
        tasks.append({"id": case.id, "dir": str(case.dir.resolve()), "params": case.params,
                      "command": case_command(case, launcher, ranks),
                      "prefix": str(case.prefix.dir.resolve()) if case.prefix else None})
    manifest = directory / "manifest.json"
    _write_json(manifest, {"study": study.settings["name"], "kind": kind, "ranks": ranks,
                           "time_limit": study.settings["time_limit"], "tasks": tasks})
    script = directory / "job.sh"
    write_text_atomic(script, sbatch_script(
        name=study.settings["name"], kind=kind, count=len(cases), ranks=ranks, manifest=manifest,
        output_dir=directory, time_limit=time_limit, partition=partition, max_concurrent=max_concurrent,
        dependency=dependency))
    done = subprocess.run(["sbatch", "--parsable", str(script)], capture_output=True, text=True)
    if done.returncode != 0:
        raise InputError(f"sbatch {script} failed: {done.stderr.strip() or done.returncode}")
    job = done.stdout.strip().split(";")[0]
    submissions = read_submissions(study) + [{"job": job, "kind": kind, "ids": [case.id for case in cases],
                                              "script": str(script), "submitted": time.time()}]
    _write_json(slurm_dir(study) / "submissions.json", submissions)
    return job


# -- status ---------------------------------------------------------------------------------------

def status(study: Study, stream=None, local: dict | None = None) -> dict:
    """Print a line per case (id, state, parameters, SLURM task) and the counts; returns the counts.

    States: ok, no_equilibrium, failed (a result), running / queued (a SLURM task of a recorded submission, or with
    `local`, the {'started': time} of a `femcontact study` running here: started by it / not yet), missing."""
    try:
        active = active_tasks(study) if read_submissions(study) else {}
    except InputError as error:
        print(f"note: {error}; SLURM states unknown", file=sys.stderr)
        active = {}
    stream = stream or sys.stdout
    counts = dict.fromkeys((*STATUSES, "running", "queued", "missing"), 0)
    for case in study.cases:
        result = read_result(case.dir)
        task = active.get(case.id)
        if result is not None:
            state = result["status"] if result["status"] in STATUSES else "failed"
        elif task:
            state = "running" if task["state"] in ("RUNNING", "COMPLETING", "CONFIGURING") else "queued"
        elif local is not None:
            state = "running" if _started(case.dir) >= local["started"] else "queued"
        else:
            state = "missing"
        counts[state] += 1
        where = f"  [job {task['job']}_{task['index']}]" if task else ""
        print(f"{case.id}  {state:7s}  {describe_params(case.params)}{where}", file=stream)
    print(f"study {study.settings['name']}: {len(study.cases)} cases: {counts['ok']} done, {counts['no_equilibrium']} "
          f"without equilibrium, {counts['failed']} failed, "
          f"{counts['running']} running, {counts['queued']} queued, {counts['missing']} missing", file=stream)
    return counts


def _started(case_dir: Path) -> float:
    """When the case's last run started (s since the epoch; 0 if never)."""
    try:
        return json.loads((case_dir / "runner.json").read_text()).get("started", 0.0)
    except (OSError, json.JSONDecodeError):
        return 0.0


# -- one array task -------------------------------------------------------------------------------

def run_task(manifest_path: Path, index: int) -> int:
    """Run entry `index` of a manifest in its case directory, as the local runner runs a case: the case
    writes result.json; a case that exits without one, or overruns the study's time limit, is recorded
    failed; SIGTERM (scancel, the job's time limit) stops the case and records nothing, so the case is
    submitted again next time. Returns 0 for an ok result, 1 otherwise."""
    manifest = json.loads(Path(manifest_path).read_text())
    task = manifest["tasks"][index]
    case_dir, ranks, limit = Path(task["dir"]), manifest["ranks"], manifest["time_limit"]
    versions = provenance()
    slurm = {"job": os.environ.get("SLURM_ARRAY_JOB_ID"), "task": index, "node": os.uname().nodename}
    if task["prefix"] is not None:
        prefix = read_result(Path(task["prefix"]))
        if prefix is None:
            print(f"case {task['id']}: shared prefix {task['prefix']} has no result (cancelled?); "
                  "nothing recorded, resubmit the study", file=sys.stderr)
            return 1
        if prefix["status"] != "ok":
            _write_json(case_dir / "runner.json", {**versions, "slurm": slurm})
            result = prefix_outcome(Path(task["prefix"]).name, prefix)
            _write_json(case_dir / "result.json", result)
            return 0 if result["status"] in ANSWERS else 1
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "femcontact-jit"
    slot, lock = take_slot(cache, "slurm-slot")
    remove_unfinished_compilations(cache, slot)
    (case_dir / "result.json").unlink(missing_ok=True)
    _write_json(case_dir / "runner.json", {**versions, "command": task["command"], "ranks": ranks,
                                           "slot": slot, "slurm": slurm, "started": time.time()})
    env = {**os.environ, "XDG_CACHE_HOME": str(cache / slot), "PYTHONUNBUFFERED": "1"}
    stop = []
    previous = signal.signal(signal.SIGTERM, lambda signum, frame: stop.append(signum))
    start = time.monotonic()
    with open(case_dir / "log.txt", "wb") as log:
        process = subprocess.Popen(task["command"], cwd=case_dir, stdout=log, stderr=subprocess.STDOUT, env=env,
                                   stdin=subprocess.DEVNULL, start_new_session=True)
    killed = None
    while process.poll() is None and not stop:
        elapsed = time.monotonic() - start
        if elapsed > limit and not killed:
            killed = f"time limit of {limit:g} s exceeded"
            signal_group(process, signal.SIGTERM)
        elif killed and elapsed > limit + 5:
            signal_group(process, signal.SIGKILL)
        time.sleep(0.05)
    result = read_result(case_dir) if not killed else None
    terminated = result is None and not killed and process.returncode in (-signal.SIGTERM, 128 + signal.SIGTERM)
    if stop or terminated:  # stopped from outside (scancel, the job's time limit): SLURM signals every process
        signal_group(process, signal.SIGTERM)
        try:
            process.wait(5)
        except subprocess.TimeoutExpired:
            signal_group(process, signal.SIGKILL)
        if read_result(case_dir) is None:
            print(f"case {task['id']}: stopped by SIGTERM; nothing recorded, it is submitted again", file=sys.stderr)
            return 143
        result = read_result(case_dir)
    signal.signal(signal.SIGTERM, previous)
    if result is None:
        reason = killed or exit_reason(process.returncode, case_dir / "log.txt")
        result = {"status": "failed", "reason": reason, "metrics": {}, "timings": {}, "info": {"ranks": ranks}}
        _write_json(case_dir / "result.json", result)
    runner = json.loads((case_dir / "runner.json").read_text())
    _write_json(case_dir / "runner.json", {**runner, "wall": time.monotonic() - start})
    lock.close()
    return 0 if result["status"] in ANSWERS else 1


if __name__ == "__main__":
    if len(sys.argv) != 4 or sys.argv[1] != "task":
        sys.exit("usage: python -m femcontact.study.slurm task MANIFEST INDEX")
    sys.exit(run_task(Path(sys.argv[2]), int(sys.argv[3])))
