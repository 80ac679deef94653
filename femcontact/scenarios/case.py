"""Run one case of any family and collect its metrics: what `femcontact run` calls.

A contact scene runs through the solver (history streamed to `history.csv`, progress on
standard error), then its family adds its own metrics (`FAMILY_METRICS`, by geometry);
an RCC scene is evaluated by the truss model.
"""
import time
from pathlib import Path

from femcontact.errors import InputError


def family_metrics(simulation) -> dict:
    """The study family's metrics of a finished contact simulation (none for a plain block):
    a peg on a compliant support is an insertion, any other peg in a hole a wedging case."""
    if "compliant_support" in simulation.scene["effects"]:
        from femcontact.scenarios.insertion import insertion_metrics

        return insertion_metrics(simulation)
    if simulation.scene["geometry"] == "peg_in_hole":
        from femcontact.scenarios.wedging import wedge_metrics

        return wedge_metrics(simulation)
    if simulation.scene["geometry"] == "snap_fit":
        from femcontact.scenarios.snap_fit import snap_fit_metrics

        return snap_fit_metrics(simulation)
    return {}


def summary_metrics(simulation) -> dict:
    """Flat metrics: every step-end output as '<step>.<quantity>', plus totals."""
    metrics = {}
    for step, row in simulation.step_end_rows().items():
        for key, value in row.items():
            if key != "step":
                metrics[f"{step}.{key}"] = value
    metrics["newton_iterations"] = sum(row["newton_iterations"] for row in simulation.history)
    metrics["increments"] = len(simulation.history)
    metrics["max_von_mises"] = max(row["max_von_mises"] for row in simulation.history)
    metrics["yielded"] = any(row["yielded"] for row in simulation.history)
    return metrics


def run_contact(scene: dict, case_dir: Path, checkpoint: bool = False, restart=None, quiet: bool = True) -> dict:
    """Run a resolved contact scene; stream history.csv, write fields.npz into case_dir.
    `checkpoint`: also save the final state in case_dir/checkpoint; `restart`: start from
    such a checkpoint (same first steps, same ranks) and run only the later steps."""
    from mpi4py import MPI

    from femcontact.outputs.fields import FieldSeries, write_fields
    from femcontact.outputs.history import HistoryWriter
    from femcontact.outputs.progress import Progress
    from femcontact.solver.stepping import Simulation

    if not scene["steps"]:
        raise InputError("steps: a contact scene needs at least one step")
    case_dir, rank = Path(case_dir), MPI.COMM_WORLD.rank
    history = HistoryWriter(case_dir / "history.csv", rank)
    listeners = [history] + ([] if quiet else [Progress(scene, rank=rank)])
    series = None
    try:
        simulation = Simulation(scene, listeners=listeners)
        first_step = simulation.load_checkpoint(restart) if restart else 0
        if scene["outputs"]["fields"]:  # frames from here on: a restart's series begins at its checkpoint
            series = FieldSeries(simulation, case_dir)
            simulation.listeners.append(series)
        if scene["geometry"] == "snap_fit":  # a jam ends the run as an outcome, not a failure
            from femcontact.scenarios.snap_fit import run as run_snap_fit

            run_snap_fit(simulation, first_step)
        else:
            simulation.run(first_step)
    finally:
        for listener in listeners:
            listener.close()
    # a full disk stops every rank, none waits below
    error = MPI.COMM_WORLD.bcast(history.error or (series and series.error), root=0)
    if error is not None:
        raise error
    if checkpoint:
        simulation.save_checkpoint(case_dir / "checkpoint")
    start = time.perf_counter()
    write_fields(simulation, case_dir)
    simulation.timings["output"] += time.perf_counter() - start
    metrics = {**summary_metrics(simulation), **family_metrics(simulation)}
    info = {"dofs": simulation.dofs, "newton_iterations": metrics["newton_iterations"],
            "effects": list(scene["effects"]), "built": simulation.problem.built,
            "stabilized_increments": simulation.stabilized_increments, "stopped": simulation.stopped}
    return {"metrics": metrics, "timings": simulation.timings, "info": info}


def run_case(scene: dict, case_dir: Path, checkpoint: bool = False, restart=None, quiet: bool = True) -> dict:
    """Run a resolved scene of any kind; returns {'metrics', 'timings', 'info'} or raises
    SimulationFailed."""
    if scene["kind"] == "rcc":
        from femcontact.rcc.device import run_case as run_rcc

        return run_rcc(scene)
    if scene["kind"] == "dislodging_beyond":
        from femcontact.scenarios.dislodging_beyond import run_case as run_beyond

        return run_beyond(scene, case_dir, checkpoint, restart)
    if scene["kind"] == "dislodging":
        from femcontact.scenarios.dislodging import run_case as run_dislodging

        return run_dislodging(scene, case_dir, checkpoint, restart)
    return run_contact(scene, case_dir, checkpoint, restart, quiet)
