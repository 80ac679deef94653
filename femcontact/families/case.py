"""Run one case of any family and collect its metrics: what `femcontact run` calls.

A scene of a family's own kind runs by the family's `run_case` (e.g. the RCC truss, a dislodging
search); a contact scene runs through the solver (history streamed to `history.csv`, progress on
standard error), stepped by its family's `run_steps` if it has one, then its family adds its own
metrics. The family comes from the registry (femcontact.families).
"""
import math
import time
from pathlib import Path

from femcontact import families
from femcontact.config.scene import friction_coefficient
from femcontact.errors import InputError


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


PRELOAD_FLOOR = 1e-3
"""Contact force left by earlier steps, relative to the failing load, above which a preload may hold
what a bare rigid peg cannot: the statics check then does not apply."""
QUARTER_TURN = 90.0
"""deg: a peg that pseudo-transient continuation turned farther than this without coming to rest
has tipped over (`carried_out`)."""
REST_FRACTION = 1e-3
"""A peg running on under a load without equilibrium is at rest once its speed falls below this
fraction of the largest it reached in the step."""


def _free_peg_in_hole(scene: dict) -> bool:
    """A rigid peg in a hole held by nothing but the hole (no compliant support)."""
    return (scene["geometry"] == "peg_in_hole" and scene["rigid"] == "peg"
            and "compliant_support" not in scene["effects"])


def statics_verdict(simulation, index: int, load) -> dict | None:
    """Whether `load` in step `index` has no static equilibrium: {'load', 'step', 'time',
    'friction_needed', 'mu'} or None (it has one, or the statics do not apply).

    The statics apply to a rigid peg placed in two-point contact (in 3-D, under a load in the
    plane of its lean: `two_point_statics.section_load`), held by nothing but the hole (no
    compliant support), with no preload left by earlier steps: then a load that needs
    more friction than mu in the configuration the peg reaches (`two_point_statics.
    reached_friction_needed`: the two-point contact if the load presses the tip corner, else
    upright against the mouth corner's wall or the opposite lean) has no equilibrium (the peg
    slides or rocks between the leans); 'friction_needed' is None where no friction holds it."""
    from femcontact.references.peg_in_hole import l_2p
    from femcontact.references.two_point_statics import reached_friction_needed, section_load

    scene = simulation.scene
    in_plane = section_load(scene["dim"], load.force, load.moment)
    if not _free_peg_in_hole(scene) or scene["peg"]["placement"] != "two_point" or in_plane is None:
        return None
    step = scene["steps"][index]
    force, couple = in_plane
    size = math.hypot(*force) + abs(couple) / l_2p(scene["peg"]["width"], scene["peg"]["insertion_depth"])
    earlier = [row for row in simulation.history if row["step"] != step["name"]]
    if not size > 0 or (earlier and max(earlier[-1]["contact_A_force"], earlier[-1]["contact_B_force"])
                        > PRELOAD_FLOOR * size):
        return None
    mu = friction_coefficient(scene)
    reached = reached_friction_needed(scene, force, couple, step["load_point"])
    if reached is None or not reached[0] > mu:
        return None
    needed, configuration = reached
    where = "in two-point contact" if configuration == "two-point contact" else \
        f"(it opens the tip's contact and turns the peg {configuration})"
    holds = f"it needs mu >= {needed:.4g}" if math.isfinite(needed) else "no friction holds it there"
    text = (f"{_load_text(step, load)} has no static equilibrium of the rigid peg {where}: {holds}, "
            f"the scene has mu = {mu:.4g}")
    return {"load": text, "step": step["name"], "time": float(load.time),
            "friction_needed": needed if math.isfinite(needed) else None, "mu": mu}


def _load_text(step: dict, load) -> str:
    """"step 'NAME' at t = ... s: the load (force [...] N at POINT, couple ... N*mm)"."""
    force, couple = (", ".join(f"{float(value):.4g}" for value in vector) for vector in (load.force, load.moment))
    couple = couple if len(load.moment) == 1 else f"[{couple}]"
    return (f"step {step['name']!r} at t = {load.time:.6g} s: the load (force [{force}] N at "
            f"{step['load_point']}, couple {couple} N*mm)")


def carried_out(simulation, failure) -> dict | None:
    """Whether the solver, before the run failed, saw the load carry the peg out of the hole: under
    pseudo-transient continuation (`Simulation.pseudo_travel`, the rigid body's travel when it gave
    up) the peg rose along the hole's axis by more than its insertion depth, or turned by more
    than a quarter turn (it tips over: no wedged pose lies that far from the lean it was placed
    in), without coming to rest. The verdict {'load', 'step', 'time', 'friction_needed' (None),
    'mu'} or None."""
    scene = simulation.scene
    travel = simulation.pseudo_travel.get(failure.step)
    if travel is None or not _free_peg_in_hole(scene):
        return None
    dim = scene["dim"]
    rise, depth = float(travel[dim - 1]), scene["peg"]["insertion_depth"]
    turn = math.degrees(math.hypot(*travel[dim:]))  # the rotation vector's length
    if rise > depth:
        carried = (f"lifts the peg out of the hole: under pseudo-transient continuation it rose by {rise:.3g} mm, "
                   f"more than its insertion depth of {depth:g} mm")
    elif turn > QUARTER_TURN:
        carried = (f"tips the peg over: under pseudo-transient continuation it turned by {turn:.3g} deg, more "
                   f"than a quarter turn")
    else:
        return None
    step = scene["steps"][failure.step]
    text = f"{_load_text(step, failure.load)} {carried}, without coming to rest"
    return {"load": text, "step": step["name"], "time": float(failure.load.time), "friction_needed": None,
            "mu": friction_coefficient(scene)}


def no_equilibrium(simulation, failure) -> dict | None:
    """Whether a quasi-static run that failed (SimulationFailed `failure`) did so because its load
    has no static equilibrium (`statics_verdict`, or the solver saw it carry the peg out of the hole:
    `carried_out`): the verdict with its 'reason', or None."""
    if failure.load is None or "inertia" in simulation.scene["effects"]:
        return None
    verdict = statics_verdict(simulation, failure.step, failure.load) or carried_out(simulation, failure)
    if verdict is None:
        return None  # an equilibrium exists (or the statics do not apply): the failure is the solver's
    message = str(failure)
    solver = message[message.find("after "):].split("; residual history")[0]  # 'after N cuts: ...'
    return {**verdict, "reason": f"{verdict['load']}; the solver found none either ({solver})"}


class RunOn:
    """With inertia, a load without a static equilibrium (`statics_verdict` at the step's end load)
    runs on dynamically until the peg leaves contact (both zones carry no force), comes to rest
    (`REST_FRACTION`) or the step ends; then the run ends (a Simulation event) and `verdict` says
    which ('run_on': 'left_contact', 'at_rest' or 'step_end')."""

    def __init__(self, simulation):
        self.simulation, self.verdicts, self.verdict = simulation, {}, None
        self.previous, self.peak = None, 0.0

    def __call__(self, index: int, row: dict) -> str:
        sim = self.simulation
        step = sim.scene["steps"][index]
        if index not in self.verdicts:
            self.verdicts[index] = statics_verdict(sim, index, sim.schedule.load(index, step["duration"], row["dt"]))
            self.previous, self.peak = None, 0.0
        verdict = self.verdicts[index]
        if verdict is None:
            return ""
        speed = self._speed(row)
        self.peak = max(self.peak, speed)
        end = sim.schedule.start_times[index] + step["duration"]
        if row["contact_A_force"] == 0 and row["contact_B_force"] == 0:
            how, said = "left_contact", "the peg left contact"
        elif self.previous is not None and self.peak > 0 and speed < REST_FRACTION * self.peak:
            how, said = "at_rest", "the peg came to rest"
        elif row["time"] >= end * (1 - 1e-12):
            how, said = "step_end", "the step ended, the peg still moving"
        else:
            self.previous = row
            return ""
        self.verdict = {**verdict, "run_on": how, "run_on_time": row["time"],
                        "reason": f"{verdict['load']}; with inertia it ran on: {said} at t = {row['time']:.6g} s"}
        return self.verdict["reason"]

    def _speed(self, row: dict) -> float:
        """The peg's speed over the increment (mm/s): its reference point's plus its rotation's at half its width."""
        if self.previous is None:
            return 0.0

        def change(names) -> float:
            return math.hypot(*(row[name] - self.previous[name] for name in names if name in row))
        moved, turned = change(("rigid_x", "rigid_y", "rigid_z")), change(("rigid_rx", "rigid_ry", "rigid_rz"))
        return (moved + turned * self.simulation.scene["peg"]["width"] / 2) / row["dt"]


def outcome_metrics(simulation, verdict: dict) -> dict:
    """Metrics of a run that ended without a static equilibrium: the converged increments' summary,
    where the load lost its equilibrium, and the family's answer to it (a wedging case: not wedged)."""
    metrics = summary_metrics(simulation) if simulation.history else {"newton_iterations": 0, "increments": 0}
    metrics.update({"no_equilibrium_step": verdict["step"], "no_equilibrium_time": verdict["time"],
                    "friction_needed": verdict["friction_needed"], "mu": verdict["mu"]})
    if "run_on" in verdict:
        metrics.update(run_on=verdict["run_on"], run_on_time=verdict["run_on_time"])
    family = families.family_of(simulation.scene)
    if family and family.outcome_metrics:
        metrics.update(family.outcome_metrics(simulation.scene))
    return metrics


def run_contact(scene: dict, case_dir: Path, checkpoint: bool = False, restart=None, quiet: bool = True) -> dict:
    """Run a resolved contact scene; stream history.csv, write fields.npz into case_dir.
    `checkpoint`: also save the final state in case_dir/checkpoint; `restart`: start from
    such a checkpoint (same first steps, same ranks) and run only the later steps. A load
    without a static equilibrium (`no_equilibrium`) ends the run as an outcome: status
    'no_equilibrium' with its reason, the fields of the last converged state."""
    from mpi4py import MPI

    from femcontact.outputs.fields import Fields, FieldSeries, write_fields
    from femcontact.outputs.history import HistoryWriter
    from femcontact.outputs.progress import Progress
    from femcontact.solver.stepping import Simulation, SimulationFailed

    if not scene["steps"]:
        raise InputError("steps: a contact scene needs at least one step")
    case_dir, rank = Path(case_dir), MPI.COMM_WORLD.rank
    history = HistoryWriter(case_dir / "history.csv", rank)
    listeners = [history] + ([] if quiet else [Progress(scene, rank=rank)])
    verdict, series, family = None, None, families.family_of(scene)
    try:
        simulation = Simulation(scene, listeners=listeners)
        first_step = simulation.load_checkpoint(restart) if restart else 0
        fields = Fields(simulation)  # fields.npz's contact values are those of the last increment
        if scene["outputs"]["fields"]:  # frames from here on: a restart's series begins at its checkpoint
            series = FieldSeries(simulation, case_dir, fields)
            simulation.listeners.append(series)
        run_on = RunOn(simulation)
        if "inertia" in scene["effects"]:
            simulation.events.append(run_on)
        try:
            simulation.run(first_step)
        except SimulationFailed as failure:
            verdict = no_equilibrium(simulation, failure)
            if verdict is None:
                failure.timings, failure.info = simulation.timings, {"newton_solves": simulation.newton_solves()}
                raise
        verdict = verdict or run_on.verdict
    finally:
        for listener in listeners:
            listener.close()
    # a full disk stops every rank, none waits below
    error = MPI.COMM_WORLD.bcast(history.error or (series and series.error), root=0)
    if error is not None:
        raise error
    if checkpoint and verdict is None:
        simulation.save_checkpoint(case_dir / "checkpoint")
    start = time.perf_counter()
    write_fields(simulation, case_dir, fields)
    simulation.timings["output"] += time.perf_counter() - start
    if verdict is None:
        metrics = {**summary_metrics(simulation), **(family.metrics(simulation) if family and family.metrics else {})}
    else:
        metrics = {**outcome_metrics(simulation, verdict), "wall_time_s": float(sum(simulation.timings.values()))}
    info = {"dofs": simulation.dofs, "newton_iterations": metrics["newton_iterations"],
            "effects": list(scene["effects"]), "built": simulation.problem.built,
            "stabilized_increments": simulation.stabilized_increments, "stopped": simulation.stopped,
            "newton_solves": simulation.newton_solves()}
    status = {} if verdict is None else {"status": "no_equilibrium", "reason": verdict["reason"]}
    return {**status, "metrics": metrics, "timings": simulation.timings, "info": info}


def run_case(scene: dict, case_dir: Path, checkpoint: bool = False, restart=None, quiet: bool = True) -> dict:
    """Run a resolved scene of any kind; returns {'metrics', 'timings', 'info'} (and 'status' and
    'reason' for an outcome other than ok) or raises SimulationFailed."""
    family = families.family_of(scene)
    if family and family.run_case:
        return family.run_case(scene, case_dir, checkpoint, restart)
    return run_contact(scene, case_dir, checkpoint, restart, quiet)
