"""femcontact command line: `femcontact COMMAND ...`.

Each command lives in its own module, imported only when called, so that
`femcontact rcc ...` never pays for importing DOLFINx. A command module
provides `add_arguments(parser)` and `command(args) -> int`.
"""
import argparse
import ctypes
import importlib
import logging
import os
import sys

from femcontact.errors import InputError

COMMANDS = {
    "run": ("femcontact.cli.run", "run one scene and write its results"),
    "study": ("femcontact.study.command", "run the cases of a study that are not done yet"),
    "report": ("femcontact.study.report", "write the plots, snapshots and summary of a study"),
    "rcc": ("femcontact.rcc.cli", "remote-centre-compliance device: wrench, displace, centre"),
    "whitney": ("femcontact.cli.whitney", "compliantly supported rigid-peg insertion (Whitney), analytic"),
    "hertz": ("femcontact.cli.hertz", "Hertz benchmark (reference §5) at one contact-zone size"),
}


THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
"""One BLAS/OpenMP thread per MPI rank unless the user set them: ranks, not threads, use the cores."""


def _warnings_and_errors(record: logging.LogRecord) -> bool:
    return record.levelno >= logging.WARNING


def quiet_logging() -> None:
    """FFCx's JIT compiles through setuptools, which logs every compiler call at INFO on the root
    logger: keep warnings and errors only, so a run's output is its progress (the filter is added
    once per process, however often this is called)."""
    logging.getLogger().addFilter(_warnings_and_errors)


def main(argv=None) -> int:
    for name in THREAD_VARIABLES:
        os.environ.setdefault(name, "1")
    quiet_logging()
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = argparse.ArgumentParser(prog="femcontact", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, (_, help_) in COMMANDS.items():
        sub.add_parser(name, help=help_, add_help=False)
    if not argv or argv[0] not in COMMANDS:
        parser.print_help() if not argv or argv[0] in ("-h", "--help") else parser.parse_args(argv)
        return 0 if argv else 2
    module = importlib.import_module(COMMANDS[argv[0]][0])
    command_parser = argparse.ArgumentParser(prog=f"femcontact {argv[0]}", description=COMMANDS[argv[0]][1])
    module.add_arguments(command_parser)
    args = command_parser.parse_args(argv[1:])
    try:
        return module.command(args) or 0
    except InputError as error:
        if launch_rank() == 0:  # under mpirun every rank finds the same error: one message
            print(f"femcontact {argv[0]}: error: {error}", file=sys.stderr)
        return 2


def console() -> None:
    """The `femcontact` program (and `python -m femcontact`): `main`, then `end_process`."""
    end_process(main())


def end_process(code: int) -> None:
    """End this process with exit status `code`, skipping the interpreter's teardown.

    Python frees every module's objects one by one at exit: with DOLFINx, UFL and PETSc loaded
    that took 0.12 s after `femcontact hertz` had printed its result (median of 5 runs, 0.13 s
    against 0.02 s). What a normal exit does that matters is done first: logging's handlers and
    Python's and C's standard streams flushed, PETSc and MPI finalised (under mpirun a rank that
    skips MPI_Finalize is reported as failed)."""
    logging.shutdown()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe: what the normal exit would have met too
            pass
    petsc = sys.modules.get("petsc4py.PETSc")
    if petsc is not None:
        petsc._finalize()
    mpi = sys.modules.get("mpi4py.MPI")
    if mpi is not None and mpi.Is_initialized() and not mpi.Is_finalized():
        mpi.Finalize()
    ctypes.CDLL(None).fflush(None)  # what C libraries printed (PETSc's -log_view at finalisation)
    os._exit(code)


RANK_VARIABLES = ("OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK")
"""Where MPI launchers (Open MPI, PMIx, MPICH/Hydra) put a process's rank, before MPI starts."""


SINGLETON_MPI = {"OMPI_MCA_ess_singleton_isolated": "1", "OMPI_MCA_pml": "ob1"}
"""Open MPI's defaults for a process started without a launcher, which runs alone and spawns no
MPI job: no helper daemon, no probing of network transports (MPI_Init to a first barrier took
0.57 s with Open MPI 4.1's defaults, 0.19 s with these, python and numpy included). A user's
own settings of these variables win."""


def start_mpi_for_meshing():
    """Start MPI for a command that builds a mesh in this process; returns mpi4py's MPI.

    gmsh's library is loaded first: loaded after MPI, PETSc and DOLFINx it took 0.8-1.2 s
    against 0.3-0.7 s (its many relocations are resolved against every library already loaded)."""
    if not any(name in os.environ for name in RANK_VARIABLES):
        for name, value in SINGLETON_MPI.items():
            os.environ.setdefault(name, value)
    import gmsh  # noqa: F401  (the load order is the point)
    from mpi4py import MPI

    return MPI


def launch_rank() -> int:
    """This process's rank in its MPI launch, read from the launcher's environment (0 outside one)."""
    for name in RANK_VARIABLES:
        if os.environ.get(name, "").isdigit():
            return int(os.environ[name])
    return 0


if __name__ == "__main__":
    console()
