"""A femcontact process's start and end: MPI started for meshing, Open MPI's singleton defaults,
no scan of the installed distributions for two version strings, the compiler's logging kept
quiet, and the end without the interpreter's teardown. Used by the command line, the study's
warm workers and the measurement programs (benchmarks/: make bench, accuracy, stability).
"""
import ctypes
import importlib
import importlib.metadata
import logging
import os
import sys
import types


def _warnings_and_errors(record: logging.LogRecord) -> bool:
    return record.levelno >= logging.WARNING


def quiet_logging() -> None:
    """FFCx's JIT compiles through setuptools, which logs every compiler call at INFO on the root
    logger: keep warnings and errors only, so a run's output is its progress (the filter is added
    once per process, however often this is called)."""
    logging.getLogger().addFilter(_warnings_and_errors)


RANK_VARIABLES = ("OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK")
"""Where MPI launchers (Open MPI, PMIx, MPICH/Hydra) put a process's rank, before MPI starts."""


SINGLETON_MPI = {"OMPI_MCA_ess_singleton_isolated": "1", "OMPI_MCA_pml": "ob1"}
"""Open MPI's defaults for a process started without a launcher, which runs alone and spawns no
MPI job: no helper daemon, no probing of network transports (MPI_Init to a first barrier took
0.57 s with Open MPI 4.1's defaults, 0.19 s with these, python and numpy included). A user's
own settings of these variables win."""


class VersionsOnly(types.ModuleType):
    """Stands in for setuptools' `pkg_resources` while only versions are asked of it. UFL 2022.2
    and FFCx 0.5 import it just for `get_distribution(name).version`, and importing it scans
    every installed distribution: a `femcontact hertz` process (1,904 dofs) took 0.70-0.72 s
    with it and 0.62-0.64 s with this stand-in (medians of 5 processes, two measurements).
    Anything else asked of it (setuptools compiling a form does) loads the real module in its
    place."""

    def get_distribution(self, name: str):
        return types.SimpleNamespace(project_name=name, version=importlib.metadata.version(name))

    def __getattr__(self, attribute: str):
        if sys.modules.get("pkg_resources") is self:
            del sys.modules["pkg_resources"]
        return getattr(importlib.import_module("pkg_resources"), attribute)


def start_mpi_for_meshing():
    """Start MPI for a command that builds a mesh in this process; returns mpi4py's MPI.

    gmsh's library is loaded first: loaded after MPI, PETSc and DOLFINx it took 0.8-1.2 s
    against 0.3-0.7 s (its many relocations are resolved against every library already loaded).
    `pkg_resources` is `VersionsOnly` until something needs more than a version."""
    if not any(name in os.environ for name in RANK_VARIABLES):
        for name, value in SINGLETON_MPI.items():
            os.environ.setdefault(name, value)
    sys.modules.setdefault("pkg_resources", VersionsOnly("pkg_resources"))
    import gmsh  # noqa: F401  (the load order is the point)
    from mpi4py import MPI

    return MPI


def launch_rank() -> int:
    """This process's rank in its MPI launch, read from the launcher's environment (0 outside one)."""
    for name in RANK_VARIABLES:
        if os.environ.get(name, "").isdigit():
            return int(os.environ[name])
    return 0


def end_process(code: int) -> None:
    """End this process with exit status `code`, skipping the interpreter's teardown.

    Python frees every module's objects one by one at exit: with DOLFINx, UFL and PETSc loaded,
    ending `femcontact hertz` after it had printed its result took 0.13 s that way and 0.02 s
    this way (medians of 5 runs). What a normal exit does that matters is done first: logging's
    handlers and Python's and C's standard streams flushed, PETSc and MPI finalised (under
    mpirun a rank that skips MPI_Finalize is reported as failed)."""
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
