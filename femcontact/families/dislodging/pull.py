"""Dislodging a wedged peg by pulling (the thesis, ch. 4).

A scene of kind "dislodging" is a 2-D peg-in-hole contact scene whose first two steps
wedge the peg (quasi-static) and whose steps 3-4 pull and observe; its `[dislodging]`
table says what one case of the study does from the wedged state, in one process
(the wedged state is computed once, or restored from the study's shared prefix):

- always: the quasi-static pull-out force (the largest pull with a quasi-static
  equilibrium, no inertia, by bisection; computed with the wedged state and kept in its
  checkpoint, so a study computes it once per case) and the 1-DOF estimates
  (`one_dof_thresholds`);
- method "continuous" / "pulse": one dynamic pull (femcontact.solver.dynamics, implicit Euler)
  per force in `forces` and per thesis magnitude in `thesis_forces` (scaled by our
  pull-out force over the thesis' continuous threshold `thesis_reference`), and a
  bisection for the threshold force (to `tolerance`).

A pull ends at the event "dislodged": both contact zones open, or the peg risen by
`rise`; the event time is located inside the increment. With the effect `plasticity` each pull
also records the largest equivalent plastic strain it added to the wedged state's
(`peeq_added`) and whether that passed `peeq_limit` (`damaging`); the search then also bisects
for the least damaging pull, and `damage_window_N` is how far above the threshold force it lies
(the pulls that free the peg without damage; <= 0: every pull that frees it damages; None: no
pull up to `no_damage_up_to_N` damages). Impulses: `impulse_Ns` is the
exact integral of the applied force from the start of the pull to the event;
`impulse_frames_Ns` the thesis' frame-quantised one, to the first output frame
(`frame` = 0.005 s) at or after the event.

With `outputs.fields = true` a case also films one pull, run once more from the wedged state
after the others: the weakest that dislodged the peg (else the strongest), as history.csv and the
ParaView time series fields.xdmf and rigid.xdmf (`femcontact animate CASE_DIR` plays it).

Each case writes pulls.csv (one row per pull) in its directory; `report.py` gathers them
into results/NAME/results.csv and thresholds.csv and draws the plots.
"""
import copy
import csv
import json
import math
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np
from mpi4py import MPI

from femcontact.effects.base import Effect


PULL_STEP, OBSERVE_STEP = 2, 3
PULLOUT_FILE = "pullout.json"  # the quasi-static pull-out, stored beside the wedged state
CONTINUATION_LOADS = 4
"""Loads from the largest one held up to a quasi-static probe whose solve from the wedged state
failed (`quasi_static_probe`)."""
RAMP_LOADS = 8
"""Loads up to the first guess of a quasi-static threshold that `largest_held` tries in turn."""


def largest_held(holds, high: float, tolerance: float, doublings: int = 0) -> tuple[float, float, int]:
    """(low, high, probes): the largest load that `holds` (magnitude -> bool) holds, bracketed to
    `tolerance`. The loads high / RAMP_LOADS, 2 high / RAMP_LOADS, ... high, then high doubled up
    to `doublings` times, are tried in turn up to the first one not held, and the bracket between
    it and the last one held is bisected: each probe has the equilibria held below it to start
    from (`quasi_static_probe`). RuntimeError if every load is held."""
    loads = [high * k / RAMP_LOADS for k in range(1, RAMP_LOADS + 1)] + [high * 2 ** j for j in range(1, doublings + 1)]
    low, probes = 0.0, 0
    for load in loads:
        probes += 1
        if not holds(load):
            high = load
            break
        low = load
    else:
        raise RuntimeError(f"the wedge holds {low:.4g}, the largest load tried")
    while high - low > tolerance * (1 + 1e-9):
        middle, probes = (low + high) / 2, probes + 1
        if holds(middle):
            low = middle
        else:
            high = middle
    return low, high, probes


def quasi_static_probe(simulation, wedged: dict, load_at, magnitude: float, held: dict, gone) -> int:
    """Newton iterations of the quasi-static equilibrium under the load `magnitude`, left solved
    (not committed). `load_at(m)` is the load of magnitude m; `held` maps magnitudes already held
    to their equilibria (`Problem.state`); `gone(travel)` says whether a change of the rigid pose
    (mm, rad) from the wedged one has let the peg go. In turn, until one converges:

    1. exact Newton from the wedged state;
    2. exact Newton from the equilibrium of the largest magnitude held below, through
       CONTINUATION_LOADS loads up to it (friction still anchored at the wedged state);
    3. the rigid body let travel from the wedged state to rest on the exact equations
       (`DynamicSimulation.settle`: pseudo-transient continuation, given up once the peg has
       gone: BodyGone).

    A Newton solve that fails is no proof that the wedge lets go: just above a threshold exact
    Newton can stall with both contacts loaded and the peg not moved (docs/dislodging_methods.md).
    Raises NewtonFailure when the last fails."""
    from femcontact.solver.newton import NewtonFailure

    simulation.resume(wedged)
    try:
        return simulation.solve(load_at(magnitude), stabilize=False)
    except (NewtonFailure, FloatingPointError):
        pass
    below = [m for m in held if m < magnitude]
    if below:
        start = max(below)
        simulation.problem.restore(held[start])
        try:
            return sum(simulation.solve(load_at(m), stabilize=False)
                       for m in np.linspace(start, magnitude, CONTINUATION_LOADS + 1)[1:])
        except (NewtonFailure, FloatingPointError):
            pass
    simulation.resume(wedged)
    return simulation.settle(load_at(magnitude), gone)

# -- impulses ------------------------------------------------------------------------------

def pull_impulse(schedule, elapsed: float) -> float:
    """Exact impulse (N*s) of the vertical applied force from the start of the pull over `elapsed` s."""
    from femcontact.solver.dynamics import step_impulse

    total, t = 0.0, elapsed
    for index in (PULL_STEP, OBSERVE_STEP):
        duration = schedule.steps[index]["duration"]
        span = min(t, duration)
        if span > 0:
            total += float(step_impulse(schedule, index, 0.0, span)[0][1])
        t -= span
    return total


def frame_time(elapsed: float, frame: float) -> float:
    """The first output frame at or after `elapsed` (s since the start of the pull)."""
    return math.ceil(elapsed / frame - 1e-9) * frame


# -- the 1-DOF model -------------------------------------------------------------------------

def wedged_contacts(row: dict, tilt: float) -> dict:
    """Normal and tangential forces on the peg (N) at A and B from a recorder row's zone
    resultants (forces of the peg on the blocks). A: block A's mouth corner on the peg's
    side, normal (cos t, sin t), tangent along the peg axis (-sin t, cos t); B: the tip
    corner on wall B, normal -x, tangent +y. Tangential forces are positive upwards."""
    on_peg_A = -np.array([row["contact_A_Fx"], row["contact_A_Fy"]])
    on_peg_B = -np.array([row["contact_B_Fx"], row["contact_B_Fy"]])
    n_A, t_A = np.array([math.cos(tilt), math.sin(tilt)]), np.array([-math.sin(tilt), math.cos(tilt)])
    return {"N_A": float(on_peg_A @ n_A), "T_A": float(on_peg_A @ t_A),
            "N_B": float(-on_peg_B[0]), "T_B": float(on_peg_B[1])}


def one_dof_thresholds(N_A: float, T_A: float, N_B: float, T_B: float, tilt: float, mu: float) -> dict:
    """A peg that only translates vertically, held by two frictional contacts with the wedged
    normal forces N and friction preloads T (positive up; they balance: T_A + T_B +
    N_A sin(tilt) = 0). A pull F adds -F/2 to each friction force (two like tangential
    springs) until one reaches -mu N: `first_slip` = 2 min_i (T_i + mu N_i). That contact then
    slides and the other holds until both slide: `full_slide` = mu (N_A + N_B) - N_A sin(tilt)
    (block A's push on the tilted side has an upward component). A peg free to turn pivots
    about the contact that still sticks once the first one slides, which unloads the wedge."""
    return {"first_slip": 2 * min(T_A + mu * N_A, T_B + mu * N_B),
            "full_slide": mu * (N_A + N_B) - N_A * math.sin(tilt)}


# -- one case ----------------------------------------------------------------------------------

def wedged_simulation(scene: dict, restart=None, checkpoint=None):
    """The wedged peg of `scene` (its steps before the pull, or read from the checkpoint
    `restart`; saved to `checkpoint` if given), with pull and observe steps appended for the
    pulls to set: (the DynamicSimulation, the wedging wall time in s)."""
    from femcontact.solver.dynamics import DynamicSimulation

    sim = DynamicSimulation(copy.deepcopy(scene), dynamic_from=PULL_STEP)
    start = time.perf_counter()
    first = sim.load_checkpoint(restart) if restart else 0
    for index in range(first, min(PULL_STEP, len(scene["steps"]))):
        sim.run_step(index, scene["steps"][index])
    wedge_time = time.perf_counter() - start
    if checkpoint:
        sim.save_checkpoint(checkpoint)
    steps = sim.scene["steps"]
    while len(steps) <= OBSERVE_STEP:  # the wedging prefix alone: pull and observe steps to set later
        steps.append({**copy.deepcopy(steps[PULL_STEP - 1]), "name": ("pull", "observe")[len(steps) - PULL_STEP]})
    return sim, wedge_time


class Puller:
    """The wedged peg of one scene and its pulls, each restarting from the wedged state."""

    def __init__(self, scene: dict, restart=None, checkpoint=None, held_pullout: bool = True):
        self.scene, self.settings = scene, scene["dislodging"]
        self.simulation, self.wedge_time = wedged_simulation(scene, restart, checkpoint)
        sim = self.simulation
        self.wedged_row = sim.history[-1]
        self.wedged = sim.snapshot()
        self.tilt = sim.problem.rigid.tilt()
        self.contacts = wedged_contacts(self.wedged_row, self.tilt)
        self.one_dof = one_dof_thresholds(**self.contacts, tilt=self.tilt, mu=scene["contact"]["mu"])
        self.rotation_mode = self.settings["rotation"]
        self.held_states = {}  # `_restraint()` -> {pull (N): equilibrium held} (`holds`)
        self.plasticity = next((c for c in sim.problem.components if c.name == "plasticity"), None)
        stored = Path(restart or "", PULLOUT_FILE)
        start = time.perf_counter()
        self.pullout = json.loads(stored.read_text()) if restart and stored.is_file() else {}
        modes = ["free"] + ["held"] * (held_pullout or self.rotation_mode == "held")
        modes += ["spring"] * (self.rotation_mode == "spring")
        for mode in modes:  # those the stored wedge (a study's shared prefix) does not have
            if "quasi_static_pullout_N" + PULLOUT_SUFFIX[mode] not in self.pullout:
                self.pullout.update({f"{key}{PULLOUT_SUFFIX[mode]}": value
                                     for key, value in self.quasi_static_pullout(mode).items()})
        self.pullout_time = time.perf_counter() - start
        self.pullout_force = self.pullout["quasi_static_pullout_N" + PULLOUT_SUFFIX[self.rotation_mode]]
        if checkpoint and sim.problem.mesh.comm.rank == 0:
            from femcontact.io import write_json_atomic

            write_json_atomic(Path(checkpoint, PULLOUT_FILE), self.pullout)
        self.before_event = None  # (force N, state) of the weakest pull that dislodged, at the start of its event's increment
        factor = self.settings["thickness"]
        rigid = sim.problem.rigid
        rigid.mass, rigid.mass_matrix = rigid.mass * factor, rigid.mass_matrix * factor

    def _set_pull(self, force: float, method: str, frequency: float) -> None:
        from femcontact.problem.loading import Schedule

        sim = self.simulation
        pull = sim.scene["steps"][PULL_STEP]
        pull["force"] = [0.0, float(force)]
        pull["moment"] = []
        pull["load_point"] = "peg_top"
        if method == "pulse":
            pull["amplitude"] = "pulse"
            pull["pulse"] = {"frequency": float(frequency), "duty": 1.0, "shape": "triangle"}
        else:
            pull["amplitude"] = "step"
        observe = sim.scene["steps"][OBSERVE_STEP]
        observe.update(force=[], moment=[], amplitude="step", load_point="peg_top")
        sim.schedule = Schedule(sim.scene, sim.problem.rigid, sim.schedule.points)

    def pull(self, force: float, method: str, frequency: float = 0.0) -> dict:
        """One dynamic pull from the wedged state; its results row."""
        from femcontact.solver.dynamics import Event

        s, sim = self.settings, self.simulation
        sim.resume(self.wedged)
        self._set_pull(force, method, frequency)
        start = time.perf_counter()
        with self.rotation(self.rotation_mode):
            outcome = sim.integrate([PULL_STEP, OBSERVE_STEP], Event(rise=s["rise"]), s["dt_max"], s["dt_min"],
                                    s["max_rise_per_increment"],
                                    settle_period=1 / frequency if method == "pulse" else 0.01)
        wall = time.perf_counter() - start
        start_time = float(sim.schedule.start_times[PULL_STEP])
        row = {"case": s["case"], "method": method, "pulse_hz": frequency if method == "pulse" else "",
               "rotation": self.rotation_mode, "force_N": float(force),
               "dislodged": outcome.event is not None, "dislodge_time_s": "", "impulse_Ns": "",
               "impulse_frames_Ns": "", "event": outcome.event or "",
               "rise_at_end_mm": float(sim.problem.rigid.values[1] - self.wedged["state"]["r"][1]),
               "increments": outcome.increments, "newton_iterations": outcome.newton_iterations,
               "settled": outcome.settled, "wall_s": wall}
        if self.plasticity is not None:
            row["peeq_added"] = self.peeq_added()
            row["damaging"] = row["peeq_added"] > s["peeq_limit"]
        if outcome.event:
            if self.before_event is None or force < self.before_event[0]:
                self.before_event = (float(force), outcome.before_event)
            elapsed = outcome.time - start_time
            row.update(dislodge_time_s=elapsed, impulse_Ns=pull_impulse(sim.schedule, elapsed),
                       impulse_frames_Ns=pull_impulse(sim.schedule, frame_time(elapsed, s["frame"])))
        return row

    def film(self, force: float, method: str, frequency: float, case_dir: Path) -> dict:
        """The pull `force` once more from the wedged state, its increments streamed to
        case_dir/history.csv and, every `outputs.every`-th and at the event, to the ParaView time
        series fields.xdmf and rigid.xdmf (`FieldSeries`, at the scene's times); its results row."""
        from femcontact.outputs.fields import FieldSeries
        from femcontact.outputs.history import HistoryWriter

        sim = self.simulation
        sim.resume(self.wedged)  # the series starts from the wedged state (slip is measured from it)
        history = HistoryWriter(Path(case_dir) / "history.csv", sim.problem.mesh.comm.rank)
        series = FieldSeries(sim, case_dir)
        sim.listeners += [history, series]
        try:
            row = self.pull(force, method, frequency)
        finally:
            for listener in (history, series):
                sim.listeners.remove(listener)
            series.detach()
            history.close()
        error = sim.problem.mesh.comm.bcast(history.error or series.error, root=0)
        if error is not None:
            raise error
        return row

    def peeq_added(self) -> float:
        """The largest equivalent plastic strain added to the wedged state's at a quadrature point."""
        peeq = self.plasticity.quadrature.peeq
        added = peeq.x.array - self.wedged["state"][f"plasticity.{peeq.name}"]
        return self.simulation.problem.mesh.comm.allreduce(float(added.max(initial=0.0)), op=MPI.MAX)

    def least_force(self, method: str, frequency: float, rows: list, column: str = "dislodged") -> tuple:
        """Bisection for the smallest peak force whose pull has `column` true (every pull appended
        to rows; pulls already in rows are reused): (low, high), the bracket it ends on, or
        (the largest force pulled, inf) when no pull up to it has `column`. The first bracket is
        `bracket` or 1 to 1.05 times the pull-out, widened by doubling steps (8 at most)."""
        s = self.settings
        pullout = self.pullout_force
        low, high = s["bracket"] or (pullout, 1.05 * pullout)
        cache = {round(row["force_N"], 6): row for row in rows}

        def holds(force):
            force = round(force, 6)
            if force not in cache:
                row = self.pull(force, method, frequency)
                row["search"] = True
                rows.append(row)
                cache[force] = row
            return cache[force][column]

        width = high - low
        for _ in range(8):
            if not holds(high):
                low, high = high, high + width
            elif low > 0 and holds(low):
                low, high = max(low - width, 0.0), low
            else:
                break
            width *= 2
        else:
            return low, math.inf
        while high - low > s["tolerance"] * (1 + 1e-9):
            middle = (low + high) / 2
            if holds(middle):
                high = middle
            else:
                low = middle
        return low, high

    def threshold(self, method: str, frequency: float, rows: list) -> dict:
        """The smallest peak force that dislodges, by `least_force`."""
        low, high = self.least_force(method, frequency, rows)
        if math.isinf(high):
            raise RuntimeError(f"no pull up to {low} N dislodges the peg")
        pulled = {round(row["force_N"], 6): row for row in rows}[round(high, 6)]
        return {"threshold_force_N": high, "bracket_N": high - low, "low_N": low,
                "impulse_at_threshold_Ns": pulled["impulse_Ns"]}

    def damage_threshold(self, method: str, frequency: float, rows: list) -> dict:
        """The smallest peak force whose pull adds more than `peeq_limit` of plastic strain, by
        `least_force` (with the effect `plasticity`); None when no pull up to `no_damage_up_to_N`
        damages."""
        low, high = self.least_force(method, frequency, rows, "damaging")
        if math.isinf(high):
            return {"damage_threshold_N": None, "damage_bracket_N": None, "no_damage_up_to_N": low}
        return {"damage_threshold_N": high, "damage_bracket_N": high - low, "no_damage_up_to_N": low}

    def damage_window(self, method: str, frequency: float, rows: list) -> dict:
        """The least freeing and the least damaging pull (`threshold`, `damage_threshold`) and
        `damage_window_N`, the second minus the first (None: no damaging pull found)."""
        found = {**self.threshold(method, frequency, rows), **self.damage_threshold(method, frequency, rows)}
        damage = found["damage_threshold_N"]
        found["damage_window_N"] = None if damage is None else damage - found["threshold_force_N"]
        return found

    def holds(self, force: float) -> bool:
        """Does the wedge hold a vertical pull `force` (N) quasi-statically (no inertia)? Yes when
        its equilibrium (`quasi_static_probe`) has both contact zones loaded and the peg lifted
        by less than `rise`, the dynamic pull's event (a compliant fixture lifts a held peg by
        tens of micrometres before it slides)."""
        from femcontact.solver.newton import NewtonFailure

        sim, p = self.simulation, self.simulation.problem
        sim.time_stepping.active = False
        duration = sim.scene["steps"][PULL_STEP]["duration"]

        def load_at(magnitude):
            self._set_pull(magnitude, "continuous", 0.0)
            load = sim.schedule.load(PULL_STEP, duration, duration)
            load.motion = self.wedged["state"]["r"].copy()  # dofs held in an experiment stay where the wedge left them
            return load

        def gone(travel):  # lifted by the rise or more (travel: the pose's change, mm and rad)
            return abs(travel[1]) >= self.settings["rise"]

        held = self.held_states.setdefault(self._restraint(), {})
        try:
            quasi_static_probe(sim, self.wedged, load_at, force, held, gone)
        except (NewtonFailure, FloatingPointError):
            return False
        if np.all(sim.zone_forces() > 0) and not gone(p.rigid.values - self.wedged["state"]["r"]):
            held[force] = p.state()
            return True
        return False

    @contextmanager
    def rotation(self, mode: str):
        """The peg's rotation during a pull: "free" (as the scene sets it), "held" at its wedged
        angle (a gripper that pulls without letting the peg turn), or restrained by a spring of
        `rotation_stiffness` about the wedged angle (`GripperSpring`: a gripper's compliance)."""
        sim = self.simulation
        p = sim.problem
        modes, components = list(p.rigid.modes), p.components
        if mode == "held":
            p.rigid.modes[2] = "held"
            sim.held = self.wedged["state"]["r"].copy()
        elif mode == "spring":
            angle = float(self.wedged["state"]["r"][2])
            p.components = [*components, GripperSpring(p, self.settings["rotation_stiffness"], angle)]
        try:
            yield
        finally:
            p.rigid.modes[:] = modes
            p.components = components
            sim.held = None

    def _restraint(self) -> tuple:
        """What restrains the peg now: the rigid body's modes and the gripper spring's stiffness
        (0 without one). Equilibria held under one restraint are no start for another's probes."""
        p = self.simulation.problem
        spring = next((c.stiffness for c in p.components if isinstance(c, GripperSpring)), 0.0)
        return tuple(p.rigid.modes), spring

    def quasi_static_pullout(self, rotation: str = "free") -> dict:
        """The largest pull the wedge holds quasi-statically, to `tolerance`, up to 1.5 times the
        1-DOF full-slide force (`largest_held`; no inertia, each force solved from the wedged
        state or from a held equilibrium below it: the same equations, friction anchored at the
        wedged state), with the peg's rotation restrained as `rotation` says (see `rotation`;
        "held" compares with the 1-DOF full-slide force)."""
        with self.rotation(rotation):
            low, high, _ = largest_held(self.holds, 1.5 * self.one_dof["full_slide"], self.settings["tolerance"])
        return {"quasi_static_pullout_N": low, "pullout_bracket_N": high - low}


PULLOUT_SUFFIX = {"free": "", "held": "_rotation_held", "spring": "_rotation_spring"}
"""The suffix of the pull-out's keys for each restraint of the peg's rotation (`Puller.rotation`)."""


class GripperSpring(Effect):
    """A rotational spring of stiffness k (N*mm/rad) between the peg and a gripper that holds it
    at the angle phi0 (rad): the moment -k (phi - phi0) on the peg. Added to the problem's
    components for a pull (`Puller.rotation`), not named in a scene."""
    name = "gripper_spring"

    def __init__(self, problem, stiffness: float, angle: float):
        super().__init__(problem)
        self.stiffness, self.angle = stiffness, angle

    def rigid_residual(self, load) -> np.ndarray:
        residual = np.zeros(len(self.problem.rigid.names))
        residual[2] = self.stiffness * (self.problem.rigid.values[2] - self.angle)
        return residual

    def rigid_stiffness(self, load) -> np.ndarray:
        n = len(self.problem.rigid.names)
        stiffness = np.zeros((n, n))
        stiffness[2, 2] = self.stiffness
        return stiffness


SNAPSHOT_STATES = ("wedged", "before_event")
"""Subdirectories of a case with a fields.npz: the wedged state (after release), and the weakest
dislodging pull (the threshold's) at the start of the increment in which the peg lets go."""


def write_snapshot_fields(puller, case_dir: Path) -> None:
    """fields.npz of the wedged state and of the state just before the event (see SNAPSHOT_STATES)."""
    from femcontact.io import make_dir
    from femcontact.outputs.fields import write_fields

    sim = puller.simulation
    states = {"wedged": puller.wedged["state"], "before_event": puller.before_event and puller.before_event[1]}
    for name in SNAPSHOT_STATES:
        if states[name] is not None:
            sim.problem.restore(states[name])
            write_fields(sim, make_dir(Path(case_dir, name)))
    sim.resume(puller.wedged)


def pull_columns() -> list[str]:
    return ["case", "method", "pulse_hz", "rotation", "force_N", "dislodged", "dislodge_time_s", "impulse_Ns",
            "impulse_frames_Ns", "event", "force_over_pullout", "thesis_force_N", "thickness_mm", "rise_at_end_mm",
            "increments", "newton_iterations", "settled", "search", "wall_s", "peeq_added", "damaging"]


def run_case(scene: dict, case_dir: Path, checkpoint: bool = False, restart=None) -> dict:
    """One study case: the wedged state (or its checkpoint), then the case's pulls or pull-out."""

    case_dir = Path(case_dir)
    s = scene["dislodging"]
    start = time.perf_counter()
    puller = Puller(scene, restart, case_dir / "checkpoint" if checkpoint else None)
    sim = puller.simulation
    metrics = {"residual_force_A": float(np.hypot(puller.wedged_row["contact_A_Fx"], puller.wedged_row["contact_A_Fy"])),
               **{f"wedged_{k}": v for k, v in puller.contacts.items()}, "tilt_deg": math.degrees(puller.tilt),
               "one_dof_first_slip_N": puller.one_dof["first_slip"], "one_dof_full_slide_N": puller.one_dof["full_slide"],
               "peg_mass_t": float(sim.problem.rigid.mass), "wedge_time_s": puller.wedge_time,
               **puller.pullout, "pullout_time_s": puller.pullout_time,
               "degree_of_wedging": puller.pullout["quasi_static_pullout_N"]  # P / (mu (N_A + N_B))
               / (scene["contact"]["mu"] * (puller.contacts["N_A"] + puller.contacts["N_B"]))}
    info = {"dofs": sim.dofs, "effects": list(scene["effects"]), "built": sim.problem.built,
            "newton_iterations": int(sum(row["newton_iterations"] for row in sim.history))}
    if len(scene["steps"]) <= PULL_STEP:
        return {"metrics": metrics, "timings": {"wedge": puller.wedge_time}, "info": info}
    rows, method = [], s["method"]
    frequency = s["pulse_hz"] if method == "pulse" else 0.0
    scale = puller.pullout_force / s["thesis_reference"]
    for force, thesis in [(f, "") for f in s["forces"]] + [(round(f * scale, 6), f) for f in s["thesis_forces"]]:
        rows.append({**puller.pull(force, method, frequency), "search": False, "thesis_force_N": thesis})
    if s["search"]:
        found = puller.damage_window if puller.plasticity is not None else puller.threshold
        metrics.update(found(method, frequency, rows))
    for row in rows:
        row.update(force_over_pullout=row["force_N"] / puller.pullout_force,
                   thickness_mm=s["thickness"])
    if MPI.COMM_WORLD.rank == 0:
        with open(case_dir / "pulls.csv", "w", newline="") as stream:
            writer = csv.DictWriter(stream, fieldnames=pull_columns(), extrasaction="ignore")
            writer.writeheader()
            writer.writerows(rows)
    if scene["outputs"]["fields"] and rows:  # the film: the weakest pull that dislodged, else the strongest
        dislodged = [row for row in rows if row["dislodged"]]
        filmed = min(dislodged, key=lambda r: r["force_N"]) if dislodged else max(rows, key=lambda r: r["force_N"])
        puller.film(filmed["force_N"], method, frequency, case_dir)
        metrics["filmed_force_N"] = filmed["force_N"]
    write_snapshot_fields(puller, case_dir)
    walls = [row["wall_s"] for row in rows]
    metrics.update(pulls=len(rows), pull_wall_mean_s=float(np.mean(walls)) if walls else 0.0,
                   pull_wall_max_s=float(np.max(walls)) if walls else 0.0)
    return {"metrics": metrics, "timings": {"wedge": puller.wedge_time, "total_case": time.perf_counter() - start},
            "info": info}
