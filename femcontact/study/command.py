"""`femcontact study STUDY.toml`: run the cases of a study that are not done, here (the runner,
runner.py) or as a SLURM job array (`--scheduler slurm`, slurm.py); `--list` and `--status` show
where the cases are. See docs/studies.md and docs/slurm.md.
"""
import fcntl
import json
import os
import signal
import sys
import time

from femcontact.errors import InputError
from femcontact.io import WriteError, describe, make_dir, read_result
from femcontact.outputs.result import status_counts
from femcontact.study import slurm
from femcontact.study.database import Database
from femcontact.study.progress import Progress
from femcontact.study.runner import Runner
from femcontact.study.study_file import Case, Study, check_launcher, describe_params, iter_cases, load_study, make_cases

MAX_CASES = 10_000
"""Cases a study may have unless --max-cases says more: each is at least a process start and a solve."""
ANNOUNCED_CASES = 1000
"""From this many cases on, the count is stated before they are checked (about a second per 1000)."""


def add_arguments(parser):
    parser.add_argument("study", help="study file (TOML)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="override a value of the base scene for every case")
    parser.add_argument("--jobs", type=int, default=None, help="cases at once (default: the study's jobs)")
    parser.add_argument("--ranks-per-case", type=int, default=None, help="MPI ranks per case")
    parser.add_argument("--retry-failed", action="store_true", help="rerun cases that failed")
    parser.add_argument("--force", action="store_true", help="rerun every case")
    parser.add_argument("--quiet", action="store_true", help="no progress output, only the summary")
    parser.add_argument("--results", default="results", help="results root (default: results)")
    parser.add_argument("--max-cases", type=int, default=MAX_CASES, metavar="N",
                        help=f"refuse a sweep of more than N cases (default {MAX_CASES}); --list has no limit")
    parser.add_argument("--list", action="store_true",
                        help="list the cases and their state as they are made, run nothing")
    parser.add_argument("--status", action="store_true",
                        help="a line per case (ok, no_equilibrium, failed, running, queued, missing) and the counts; "
                             "rebuilds the database and CSV; runs nothing")
    parser.add_argument("--launcher", default=None,
                        help="command prefix starting an MPI job of {ranks} ranks (default: the study's "
                             "launcher; with --scheduler slurm: 'srun -n {ranks}')")
    slurm = parser.add_argument_group("SLURM (docs/slurm.md)")
    slurm.add_argument("--scheduler", choices=("local", "slurm"), default="local",
                       help="slurm: submit the cases not done as a job array and return")
    slurm.add_argument("--partition", default="", help="SLURM partition (default: the cluster's)")
    slurm.add_argument("--time", default=None, metavar="HH:MM:SS",
                       help="time limit per array task (default: the study's time_limit + 5 min)")
    slurm.add_argument("--max-concurrent", type=int, default=None, metavar="K",
                       help="array tasks running at once (default: the study's jobs; 0 = no limit)")


def command(args) -> int:
    if args.jobs is not None and args.jobs < 0:
        raise InputError(f"--jobs {args.jobs}: expected >= 0 (0 = cores // ranks per case)")
    if args.ranks_per_case is not None and args.ranks_per_case < 1:
        raise InputError(f"--ranks-per-case {args.ranks_per_case}: expected >= 1")
    if args.launcher is not None and check_launcher(args.launcher):
        raise InputError(f"--launcher {args.launcher!r}: {check_launcher(args.launcher)}")
    if args.max_cases < 1:
        raise InputError(f"--max-cases {args.max_cases}: expected >= 1")
    study = load_study(args.study, args.set, args.results, max_cases=None if args.list else args.max_cases,
                       resolve_cases=False)
    settings = study.settings
    ranks = args.ranks_per_case if args.ranks_per_case is not None else settings["ranks_per_case"]
    jobs = args.jobs if args.jobs is not None else settings["jobs"]
    if args.launcher is not None:
        settings["launcher"] = args.launcher
    if args.list:  # reads the case directories only: works on a read-only results directory
        return _list(study)
    if not args.quiet and study.count >= ANNOUNCED_CASES:
        print(f"study {settings['name']}: {study.count} cases in the sweep; checking them", file=sys.stderr, flush=True)
    make_cases(study)
    if args.status:
        return _status(study)
    max_concurrent = args.max_concurrent if args.max_concurrent is not None else jobs  # SLURM: 0 = no limit
    jobs = jobs or max(1, len(os.sched_getaffinity(0)) // ranks)
    make_dir(study.results)
    try:
        lock = open(study.results / ".lock", "a+")  # not "w": the running study's entry must stay
    except OSError as error:
        raise WriteError(describe(error, study.results / ".lock")) from None
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        raise InputError(f"{study.results}: another `femcontact study` is running this study") from None
    try:  # who runs the study since when: --status tells its running cases from those still queued
        lock.truncate(0)
        lock.write(json.dumps({"pid": os.getpid(), "started": time.time()}))
        lock.flush()
    except OSError as error:
        raise WriteError(describe(error, study.results / ".lock")) from None

    database = Database(study.database, study.keys)
    try:
        return _run(study, args, database, jobs, ranks, max_concurrent)
    finally:
        database.close()
        lock.close()


def _run(study: Study, args, database, jobs: int, ranks: int, max_concurrent: int) -> int:
    """Run (or submit) the cases of a locked study that need it; returns the exit code."""
    settings = study.settings
    database.rebuild(study.cases)  # the case directories are the truth
    if args.scheduler == "slurm":
        return _submit(study, args, ranks, max_concurrent)
    slurm.refuse_if_in_slurm(study)
    todo = [case for case in study.cases if _needs_run(case, args)]
    prefixes = list({case.prefix.id: case.prefix for case in todo if case.prefix is not None
                     and (args.force or (read_result(case.prefix.dir) or {}).get("status") != "ok")}.values())
    if not args.quiet:
        print(f"study {settings['name']}: {len(study.cases)} cases, {len(study.cases) - len(todo)} done, "
              f"{len(todo)} to run" + (f" (+{len(prefixes)} shared prefixes)" if prefixes else "")
              + f", {jobs} at a time x {ranks} rank(s)", file=sys.stderr)
    progress = Progress(len(todo), args.quiet)
    runner = Runner(study, jobs, ranks, database, progress)
    previous = signal.signal(signal.SIGTERM, _raise_interrupt)
    try:
        runner.run(todo, prefixes)
    except KeyboardInterrupt:
        progress.close()
        runner.stop_all()
        database.export_csv(study.results / "results.csv")
        print(f"study {settings['name']}: interrupted after {progress.done} of {len(todo)} cases; "
              "run the same command again to continue", file=sys.stderr)
        return 130
    except InputError as error:  # disk full, read-only, launcher gone: stop, keep what is recorded
        progress.close()
        runner.stop_all()
        raise type(error)(f"study {settings['name']}: stopped after {progress.done} of {len(todo)} cases: {error}; "
                          "every finished case is recorded; run the same command again to continue") from None
    finally:
        signal.signal(signal.SIGTERM, previous)
    progress.close()
    database.export_csv(study.results / "results.csv")
    return _summary(study, progress.start)


def local_run(study: Study) -> dict | None:
    """The `femcontact study` running this study here ({'pid', 'started'}), or None."""
    try:
        lock = open(study.results / ".lock")
    except OSError:
        return None
    with lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_SH | fcntl.LOCK_NB)
            return None  # nobody holds it
        except BlockingIOError:
            pass
        try:
            return json.loads(lock.read())
        except json.JSONDecodeError:  # held by a runner that has not written its entry yet
            return {"pid": None, "started": time.time()}


def _status(study: Study) -> int:
    make_dir(study.results)
    database = Database(study.database, study.keys)
    try:
        database.rebuild(study.cases)
        database.export_csv(study.results / "results.csv")
    finally:
        database.close()
    slurm.status(study, local=local_run(study))
    return 0


def _submit(study: Study, args, ranks: int, max_concurrent: int) -> int:
    if max_concurrent < 0:
        raise InputError(f"--max-concurrent {max_concurrent}: expected >= 0")
    return slurm.submit(study, ranks=ranks, launcher=args.launcher or slurm.DEFAULT_LAUNCHER,
                        time_limit=slurm.parse_time(args.time) if args.time is not None
                        else slurm.default_time(study.settings["time_limit"]),
                        partition=args.partition, max_concurrent=max_concurrent,
                        retry_failed=args.retry_failed, force=args.force, quiet=args.quiet)


def _needs_run(case: Case, args) -> bool:
    result = read_result(case.dir)
    return args.force or result is None or (args.retry_failed and result["status"] == "failed")


def _raise_interrupt(signum, frame):
    raise KeyboardInterrupt


def _list(study: Study) -> int:
    """A line per case as it is made (a large sweep starts printing at once and is never held in memory)."""
    if study.count >= ANNOUNCED_CASES:
        print(f"study {study.settings['name']}: {study.count} cases in the sweep", file=sys.stderr, flush=True)
    for case in iter_cases(study):
        result = read_result(case.dir)
        print(f"{case.id}  {result['status'] if result else 'todo':6s}  {describe_params(case.params)}")
    return 0


def _summary(study: Study, start: float) -> int:
    """Counts of ok, no_equilibrium (an answer: the load has no static equilibrium) and failed
    cases, a line per case that is not ok; exit code 1 if any failed."""
    results = [(case, read_result(case.dir)) for case in study.cases]
    counts = status_counts(result for _, result in results)
    print(f"study {study.settings['name']}: {len(results)} cases, {counts['ok']} ok, {counts['no_equilibrium']} "
          f"without equilibrium, {counts['failed']} failed ({time.monotonic() - start:.1f} s)")
    for case, result in results:
        if result["status"] != "ok":
            what = "failed" if result["status"] == "failed" else "no equilibrium"
            print(f"  {what} {case.id} {describe_params(case.params)}: {result['reason']} (log: {case.dir / 'log.txt'})")
    print(f"results: {study.database} and {study.results / 'results.csv'}; cases in {study.results / 'cases'}/")
    return 1 if counts["failed"] else 0
