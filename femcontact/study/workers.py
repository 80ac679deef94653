"""Warm workers: long-lived processes that run a study's one-rank cases one after another.

A fresh `mpirun -n 1 femcontact run` pays MPI, Python and import start-up (mpi4py, DOLFINx,
UFL, gmsh) before its first assembly, for every case. A worker pays it once: it imports
those modules when it starts, then runs each case it is sent exactly as `femcontact run`
would (`femcontact.cli.main` with the same arguments, in the case directory, its stdout and
stderr appended to the case's log.txt) and, between cases, puts back what a case leaves in a
process: PETSc options it set, UFL's object counters, the gmsh session (with its options), the
working directory, garbage.

Protocol: the runner writes one JSON line per case on the worker's stdin,
{"dir": CASE_DIR, "argv": ["run", "scene.toml", "--out", ".", ...]}, and reads one JSON line
{"code": EXIT_CODE} on its stdout when the case is over. A worker that dies (a crash, os._exit)
or is killed for the time limit ends its case as a fresh process would (the runner records it
failed with the reason) and is replaced by a new one for its slot's next case.
"""
import ctypes
import gc
import importlib
import json
import os
import select
import signal
import subprocess
import sys
import traceback
from pathlib import Path

ENTRY = "femcontact.cli:main"
"""What a worker calls per case: `module:function`, function(argv) -> exit code."""

PRELOAD = ("femcontact.process:start_mpi_for_meshing", "femcontact.cli.run", "femcontact.families.case",
           "femcontact.solver.stepping", "femcontact.outputs.fields", "femcontact.outputs.history",
           "femcontact.outputs.progress")
"""What a worker imports (`module`) or calls (`module:function`) before its first case: what a
fresh process spends its start-up on, MPI started as `femcontact run` starts it (gmsh's library
first; Open MPI's singleton defaults, as the worker runs without a launcher)."""

CASES_PER_WORKER = 100
"""A worker is replaced after this many cases: its resident memory grows by about 2.6 MB per
632-dof 2-D case (measured; in DOLFINx/PETSc's own memory, not in Python objects)."""


class Worker:
    """The runner's end of one worker process (started in its own session, like a case's launcher)."""

    def __init__(self, env: dict, preexec_fn=None):
        self.process = subprocess.Popen([sys.executable, "-m", "femcontact.study.workers", ENTRY, *PRELOAD],
                                        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                        env=env, start_new_session=True, preexec_fn=preexec_fn)
        self.reply = b""
        self.cases = 0  # cases sent to it

    @property
    def pid(self) -> int:
        return self.process.pid

    @property
    def alive(self) -> bool:
        return self.process.poll() is None

    def submit(self, directory: Path, argv: list[str]) -> None:
        """Start `femcontact ARGV` in `directory`; a worker found dead meanwhile reports it in poll()."""
        try:
            self.process.stdin.write((json.dumps({"dir": str(directory), "argv": argv}) + "\n").encode())
            self.process.stdin.flush()
            self.cases += 1
        except OSError:  # BrokenPipeError: it died since the runner last looked
            pass

    def poll(self) -> int | None:
        """The case's exit code once it is over (the worker's own exit status if it died), else None."""
        stdout = self.process.stdout.fileno()
        while select.select([stdout], [], [], 0)[0]:
            data = os.read(stdout, 4096)
            if not data:  # end of file: the worker is gone or going
                break
            self.reply += data
            if b"\n" in self.reply:
                line, self.reply = self.reply.split(b"\n", 1)
                return json.loads(line)["code"]
        return self.process.poll()

    def close(self) -> None:
        """End the worker: it leaves when its stdin closes; killed if it has not after 5 s."""
        try:
            self.process.stdin.close()
        except OSError:
            pass
        try:
            self.process.wait(5)
        except subprocess.TimeoutExpired:
            try:
                os.killpg(self.process.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            self.process.wait()
        self.process.stdout.close()


class Pool:
    """One worker per job slot, started when the slot first needs one and replaced when it has died
    (crashed, or killed for the time limit) or has run CASES_PER_WORKER cases. `environment(slot)`
    is the environment of a slot's processes (its own JIT cache)."""

    def __init__(self, environment, preexec_fn=None):
        self.environment, self.preexec_fn = environment, preexec_fn
        self.workers: dict[int, Worker] = {}

    def worker(self, slot: int) -> Worker:
        """The slot's worker, a new one if it has none alive or its worker has run enough cases."""
        worker = self.workers.get(slot)
        if worker is None or not worker.alive or worker.cases >= CASES_PER_WORKER:
            if worker is not None:
                worker.close()
            worker = self.workers[slot] = Worker(self.environment(slot), self.preexec_fn)
        return worker

    def close(self) -> None:
        for worker in self.workers.values():
            worker.close()
        self.workers.clear()


# -- the worker process ---------------------------------------------------------------------------

def serve(entry: str, preload: list[str]) -> None:
    """Run cases read from stdin until it closes. Outside a case, stdin, stdout and stderr are
    /dev/null; requests and replies go through private copies of the original stdin and stdout."""
    requests, replies = os.fdopen(os.dup(0), "r"), os.fdopen(os.dup(1), "w")
    quiet = os.open(os.devnull, os.O_RDWR)
    for fd in (0, 1, 2):
        os.dup2(quiet, fd)
    for name in preload:
        try:
            if ":" in name:
                _function(name)()
            else:
                importlib.import_module(name)
        except Exception:  # the case that needs it meets the error again, in its own log
            pass
    gc.collect()
    gc.freeze()  # what is loaded now stays: a collection after a case looks at the case's objects only
    home, baseline = os.getcwd(), process_state()
    for line in requests:
        request = json.loads(line)
        code = _run_case(entry, request["dir"], request["argv"], quiet)
        os.chdir(home)
        clean_up(baseline)
        replies.write(json.dumps({"code": code}) + "\n")
        replies.flush()


def _function(spec: str):
    """The function a `module:function` spec names (its module imported)."""
    module, function = spec.split(":")
    return getattr(importlib.import_module(module), function)


def _run_case(entry: str, directory: str, argv: list[str], quiet: int) -> int:
    """entry(argv) in `directory` with stdout and stderr appended to its log.txt; the exit code a
    process running it would have."""
    log = os.open(os.path.join(directory, "log.txt"), os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    os.dup2(log, 1)
    os.dup2(log, 2)
    os.close(log)
    try:
        os.chdir(directory)
        return _function(entry)(argv) or 0
    except SystemExit as exit:  # as the interpreter ends a process: an int code, or a message and 1
        if exit.code is None or isinstance(exit.code, int):
            return exit.code or 0
        print(exit.code, file=sys.stderr)
        return 1
    except BaseException:
        traceback.print_exc()
        return 1
    finally:
        _flush()
        os.dup2(quiet, 1)
        os.dup2(quiet, 2)


def _flush() -> None:
    """Flush Python's and C's standard streams, so nothing of one case reaches the next one's log."""
    sys.stdout.flush()
    sys.stderr.flush()
    ctypes.CDLL(None).fflush(None)


def process_state() -> dict:
    """What a case may change in the process, as it is now: PETSc's options and UFL's counters.

    UFL numbers every Coefficient, Constant, Index, Label and mesh it creates, process-wide, and
    orders the operands of a sum by their text, counts included: once a count gains a digit (seen
    at the 8th 2-D wedging case in one process) a form's terms come in another order than in a
    fresh process, so its signature differs and it is compiled again."""
    state = {"petsc": {}, "ufl": {}}
    if "petsc4py.PETSc" in sys.modules:
        state["petsc"] = sys.modules["petsc4py.PETSc"].Options().getAll()
    if "ufl.classes" in sys.modules:
        state["ufl"] = {(cls, name): cls.__dict__[name] for cls in vars(sys.modules["ufl.classes"]).values()
                        if isinstance(cls, type) for name in ("_globalcount", "_ufl_global_id")
                        if name in cls.__dict__}
    return state


def clean_up(baseline: dict) -> None:
    """Undo what a case leaves in the process: PETSc options and UFL counters back to `baseline`
    (process_state() before the first case), gmsh's session ended (its options back to their
    defaults), the case's objects collected."""
    gc.collect()  # first: nothing of the case is left to use a counter again
    if "petsc4py.PETSc" in sys.modules:
        database = sys.modules["petsc4py.PETSc"].Options()
        for key in database.getAll():
            if key not in baseline["petsc"]:
                database.delValue(key)
        for key, value in baseline["petsc"].items():
            database.setValue(key, value)
    for (cls, name), value in baseline["ufl"].items():
        setattr(cls, name, value)
    if "geometry.gmsh_tools" in sys.modules:
        sys.modules["geometry.gmsh_tools"].reset()


if __name__ == "__main__":
    serve(sys.argv[1], sys.argv[2:])
    from femcontact.process import end_process

    end_process(0)  # the runner waits for its workers to end: no interpreter teardown (0.1-0.3 s)
