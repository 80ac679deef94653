"""femcontact command line: `femcontact COMMAND ...`.

Each command lives in its own module, imported only when called, so that
`femcontact rcc ...` never pays for importing DOLFINx. A command module
provides `add_arguments(parser)` and `command(args) -> int`.
"""
import argparse
import importlib
import os
import sys

from femcontact.errors import InputError
from femcontact.process import end_process, launch_rank, quiet_logging

COMMANDS = {
    "run": ("femcontact.cli.run", "run one scene and write its results"),
    "study": ("femcontact.study.command", "run the cases of a study that are not done yet"),
    "report": ("femcontact.study.report", "write the plots, snapshots and summary of a study"),
    "animate": ("femcontact.outputs.animation", "film of a run (MP4 and GIF): stress, both bodies, forces"),
    "rcc": ("femcontact.families.rcc.cli", "remote-centre-compliance device: wrench, displace, centre"),
    "whitney": ("femcontact.cli.whitney", "compliantly supported rigid-peg insertion (Whitney), analytic"),
    "hertz": ("femcontact.families.hertz.cli", "Hertz benchmark (docs/references.md) at one contact-zone size"),
}


THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
"""One BLAS/OpenMP thread per MPI rank unless the user set them: ranks, not threads, use the cores."""


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


if __name__ == "__main__":
    console()
