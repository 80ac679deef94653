"""Rigid-body dynamics through contact changes (stick, slip, separation, impact).

Scheme: implicit Euler (theta = 1) for the rigid body's velocity, the deformable
bodies quasi-static, contact by the scene's position-level Nitsche terms:

    M (v1 - v0) = dt (F(t1) + G(q1)),   q1 = q0 + dt v1

with F the applied load and G the contact force of the blocks, both at the end of the
increment (theta = 1 throughout, as in Moreau-Jean's scheme; here with position-level
contact). Increments end on the kinks of the load (pulse start, peak, end), so a
pulse's peak is applied exactly; the reported impulses are exact integrals of the
load (`step_impulse`), not the scheme's sums. Why this scheme:

- it cannot gain energy: for a convex stored energy U (elastic blocks + penalty-like
  contact) and a dissipative friction return map, E1 - E0 <= -|v1 - v0|^2_M / 2, so
  stick -> slip -> separation and impacts are stable for every dt (Newmark's
  trapezoidal rule is not: it conserves energy only for smooth problems and its
  position-level contact can inject energy at each closing of a contact);
- the blocks are quasi-static because their lowest eigenperiod (about 4 x 20 mm /
  4.9e6 mm/s = 16 us for 20 mm stainless blocks) is 1e-3 of the pulse periods; the peg on
  the contact stiffness oscillates at ~35 us, which the scheme damps (its amplitude,
  F/k ~ 1e-4 mm, is below anything the study measures);
- a free body is linear: one Newton step (no trust-region cap, M/dt^2 regularises S).

The integrator drives the quasi-static machinery through its public hooks:
`SchurNewton.time_step_stiffness` (M/dt^2 while inertia is on: the plain rigid step and the
inertia term's round-off floor), `SchurNewton.options` (fewer Newton iterations per increment),
`Simulation.prescribe`, `Simulation.record` and `Simulation.stabilized_solve`.

Output: with listeners (history file, ParaView time series), each accepted increment's row goes
to them as in `Simulation.run_step`, and the state at the event closes the output; without, no row
is computed.

Events: `integrate` stops at the first event (the peg risen by a distance, or all
contact zones open), located inside the increment by re-solving the increment with a
shorter dt (secant on the rise; bisection for the opening) and never integrates after it.
"""
from dataclasses import dataclass, field, replace

import numpy as np

from femcontact.errors import InputError
from femcontact.solver.newton import NewtonFailure
from femcontact.solver.stepping import Simulation

DYNAMIC_ITERATIONS = 12
"""Newton iterations allowed per dynamic increment before dt is cut: a short increment
converges in a few, a long one through a contact change may not converge at all, so failing
fast and cutting dt is cheaper than iterating."""


# -- exact integrals of the load amplitudes ------------------------------------------------

def pulse_integral(t: float, frequency: float, duty: float, shape: str) -> float:
    """Integral of `loading.pulse` from 0 to t (s)."""
    period = 1.0 / frequency
    whole, phase = divmod(t * frequency, 1.0)
    unit = {"triangle": 0.5, "square": 1.0, "haversine": 0.5}[shape]
    x = min(phase / duty, 1.0)
    partial = {"triangle": x * x if x <= 0.5 else 0.5 - (1 - x) ** 2,
               "square": x,
               "haversine": x / 2 - np.sin(2 * np.pi * x) / (4 * np.pi)}[shape]
    return (whole * unit + partial) * duty * period


def amplitude_integral(step: dict, t: float) -> float:
    """Integral over [0, t] of the step's amplitude factor (loading.Schedule._factor)."""
    if step["amplitude"] == "pulse":
        return pulse_integral(t, **step["pulse"])
    if step["amplitude"] == "step":
        return t
    return t * t / (2 * step["duration"])


def step_impulse(schedule, index: int, t0: float, t1: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact impulse of the step's force (N*s) and moment (N*mm*s) over [t0, t1] (s since the step began)."""
    step = schedule.steps[index]
    start, target = schedule.start_values[index]
    integral = amplitude_integral(step, t1) - amplitude_integral(step, t0)
    out = []
    for key in ("force", "moment"):
        if step["amplitude"] == "pulse":
            out.append(target[key] * integral)
        else:
            out.append(start[key] * (t1 - t0) + (target[key] - start[key]) * integral)
    return out[0], out[1]


def kinks(step: dict) -> np.ndarray:
    """Times (s since the step began) where the step's amplitude has a kink or a jump:
    the start, peak and end of every pulse."""
    if step["amplitude"] != "pulse":
        return np.zeros(0)
    period, duty = 1 / step["pulse"]["frequency"], step["pulse"]["duty"]
    starts = np.arange(0.0, step["duration"], period)
    return np.unique(np.r_[starts, starts + duty * period / 2, starts + duty * period])


# -- the increments' ends -------------------------------------------------------------------

def increment_marks(times, duration: float, dt_min: float) -> np.ndarray:
    """Sorted times (s since the step began) every increment must end on: `times` inside the
    step and its end `duration`, any two closer than `dt_min` merged (into the later one)."""
    times = np.sort(np.asarray(times, dtype=float))
    times = times[(times > 0) & (times < duration - dt_min)]
    keep = np.r_[np.diff(times) >= dt_min, True] if len(times) else np.zeros(0, bool)
    return np.r_[times[keep], duration]


def increment_end(t: float, dt: float, marks: np.ndarray, dt_min: float) -> float:
    """End of the increment from `t` of nominal length `dt`: the next mark if it comes first or
    would be left less than `dt_min` away (the increment is stretched by < dt_min), else t + dt.
    Ends on a mark are the mark itself, so the step time never drifts from the marks; an end
    t + dt off every mark leaves at least dt_min to the next one, so no increment is shorter
    than dt_min except when dt itself is: t + dt summed over increments would drift from the
    marks, and an increment left between the drifted end and a mark could be so short (1e-11 s)
    that M / dt^2 swamps the residual and Newton cannot converge."""
    mark = marks[np.searchsorted(marks, t, side="right")]
    return float(mark) if mark - (t + dt) < dt_min else t + dt


# -- events --------------------------------------------------------------------------------

@dataclass
class Event:
    """Stop when the rigid body's reference point has risen by `rise` (mm) since the start of
    `integrate`, or (`open_zones`) when every contact zone carries no force."""
    rise: float = 0.0
    open_zones: bool = True
    time_tolerance: float = 1e-6  # s, bracket left by the event location
    rise_tolerance: float = 1e-6  # relative tolerance on the rise at the located event


@dataclass
class Outcome:
    """Result of `integrate`: the event (None if none), its time (s, global) and the trace."""
    event: str | None
    time: float | None
    increments: int = 0
    newton_iterations: int = 0
    settled: bool = False  # a periodic (sticking) motion was recognised and the rest skipped
    trace: list = field(default_factory=list)  # (time s, rise mm, velocity mm/s, zone forces N..., monitor)
    before_event: dict | None = None  # the problem's state at the start of the increment holding the event


class DynamicSimulation(Simulation):
    """A Simulation stepped with implicit Euler for the rigid body, with events.

    Steps before `dynamic_from` are quasi-static (the scene's usual stepping, inertia off);
    from it on `integrate` advances with inertia and stops at the event."""

    def __init__(self, scene: dict, dynamic_from: int, comm=None):
        from mpi4py import MPI

        super().__init__(scene, comm or MPI.COMM_WORLD)
        self.held = None  # pose (mm, rad) at which dofs that are not free are held, instead of steps.motion
        self.time_stepping = self.problem.time_stepping  # the effect that gives the rigid body its mass
        if self.time_stepping is not None:
            if self.time_stepping.deformable:
                raise InputError("dynamics.deformable_inertia = true: the implicit-Euler dynamics keeps the "
                                 "deformable body quasi-static; set it false")
            self.time_stepping.scheme, self.time_stepping.active = "euler", False
            self.newton.time_step_stiffness = self._time_step_stiffness
        # the quasi-static steps must not depend on the later (dynamic) ones: the stabilisation
        # tolerance is relative to the peak load of the quasi-static steps only
        self.peak_load = self.peak_load_of(self.schedule.steps[:dynamic_from])

    def _time_step_stiffness(self) -> np.ndarray | None:
        """M / dt^2 per rigid dof (N/mm, N*mm/rad^2) while inertia is on, else None."""
        if not self.time_stepping.active:
            return None
        return np.abs(np.diag(self.problem.rigid.mass_matrix)) / self.time_stepping.dt ** 2

    @property
    def velocity(self) -> np.ndarray:
        """The rigid body's velocity at the last committed increment (mm/s, rad/s)."""
        return self.time_stepping.velocity

    # -- state kept in memory: every pull restarts from the wedged state ----------------------
    def snapshot(self) -> dict:
        return {"state": self.problem.state(), "history": len(self.history)}

    def resume(self, snapshot: dict) -> None:
        self.problem.restore(snapshot["state"])
        del self.history[snapshot["history"]:]

    # -- one increment, no output row ------------------------------------------------------
    def _begin(self, load) -> dict:
        """Start an increment from the committed state (returned, to restore on failure)."""
        state = self.problem.state()
        if self.held is not None:
            load.motion = self.held.copy()
        self.problem.begin_increment(load)
        self.prescribe(load)
        return state

    def solve(self, load, stabilize: bool = True) -> int:
        """Solve one increment from the committed state (left solved, not committed). With
        inertia a failed Newton iteration raises at once (the caller cuts dt: M/dt^2 makes
        a short increment well-posed); without, the stabilised continuation is tried
        (unless `stabilize` is false)."""
        p = self.problem
        state = self._begin(load)
        dynamic = self.time_stepping is not None and self.time_stepping.active
        try:
            try:
                return self.newton.solve(load)
            except NewtonFailure:
                if dynamic or not stabilize:
                    raise
                p.restore(state)
                self.prescribe(load)
                return self.stabilized_solve(load)
        except BaseException:
            p.restore(state)
            raise

    def settle(self, load, gone) -> int:
        """Solve a quasi-static load from the committed state by letting the rigid body travel
        to rest (`pseudo_transient_solve`), given up (BodyGone) once `gone(travel)` (the pose's
        change, mm and rad) is true. Left solved on the exact equations, not committed; a body
        that comes to rest only while the stabilisation spring holds it, where the exact
        equations then fail, is a NewtonFailure: near an equilibrium is not in one."""
        p = self.problem
        state = self._begin(load)
        self.stabilization_force = 0.0
        exhausted = self.pseudo_transient_exhausted
        try:
            iterations = self.pseudo_transient_solve(load, persist=True, gone=gone)
            if self.stabilization_force > 0:
                raise NewtonFailure(f"the rigid body came to rest by pseudo-transient continuation only with a "
                                    f"stabilisation force of {self.stabilization_force:.3g} N", [])
            return iterations
        except BaseException:
            p.restore(state)
            raise
        finally:
            self.pseudo_transient_exhausted = exhausted

    def accept(self, load) -> None:
        """Commit the solved increment (friction anchors, corners, velocity, pose)."""
        self.problem.commit(load.dt)

    def zone_forces(self) -> np.ndarray:
        """|contact force| per zone (N) of the last assembled contact vector."""
        contact = self.newton.b_contact.array_r.reshape(-1, self.problem.dim)
        comm = self.problem.mesh.comm
        return np.array([np.linalg.norm([comm.allreduce(float(contact[mask, k].sum()))
                                         for k in range(self.problem.dim)])
                         for mask in self.recorder.zones.values()])

    # -- the dynamic run -----------------------------------------------------------------
    def integrate(self, steps: list[int], event: Event, dt_max: float, dt_min: float,
                  max_rise_per_increment: float, settle_period: float = 0.01,
                  settle_tolerance: float = 1e-7, monitor=None) -> Outcome:
        """Advance through `steps` (indices) with inertia until `event`.

        Increments end on the pulse kinks (start, peak, end of each pulse), so the peak load
        is applied exactly. dt starts at dt_max; it is divided by 4 on a solver failure (down
        to dt_min; Newton gets at most `DYNAMIC_ITERATIONS` iterations), also one while locating
        the event inside the increment (its re-solves start from the increment's start), cut when an increment
        raises the body by more than `max_rise_per_increment` (mm; to 0.8 of it for a lift
        growing like dt^2), and doubled back after an increment of at most 8 iterations.
        A step whose load is periodic (a pulse train; a constant load with any period,
        `settle_period` used) is left early when the pose at the end of a period differs from
        the one a period before by less than `settle_tolerance` (mm; rotations times the body
        size): the motion is then periodic (the body sticks through every period) and the rest
        of the step repeats it. `monitor()`, if given, is called after every accepted
        increment and its value appended to that increment's trace entry."""
        if self.time_stepping is None:
            raise InputError("effects: the dynamic pull needs 'inertia'")
        options = self.newton.options
        self.newton.options = replace(options, max_iterations=min(options.max_iterations, DYNAMIC_ITERATIONS))
        self.time_stepping.active = True
        try:
            return self._integrate(steps, event, dt_max, dt_min, max_rise_per_increment, settle_period,
                                   settle_tolerance, monitor)
        finally:
            self.newton.options = options

    def _integrate(self, steps, event, dt_max, dt_min, max_rise_per_increment, settle_period,
                   settle_tolerance, monitor) -> Outcome:
        p = self.problem
        weights = p.rigid_arms
        y0 = float(p.rigid.values[1])
        outcome = Outcome(None, None)
        dt = dt_max
        for index in steps:
            step = self.schedule.steps[index]
            duration = step["duration"]
            period = (1 / step["pulse"]["frequency"] if step["amplitude"] == "pulse"
                      else settle_period if step["amplitude"] == "step" else None)
            checks = list(np.arange(1, int(duration / period + 1e-9) + 1) * period) if period else []
            marks = increment_marks(np.r_[kinks(step), checks], duration, dt_min)
            checks = [marks[np.abs(marks - c).argmin()] for c in checks]
            reference = p.rigid.values.copy()
            t = 0.0
            while t < duration:
                end = increment_end(t, dt, marks, dt_min)
                dt = end - t
                load = self.schedule.load(index, end, dt)
                committed = p.state()
                try:
                    iterations = self.solve(load)
                except (NewtonFailure, RuntimeError, FloatingPointError):
                    if dt <= dt_min:
                        raise
                    dt = max(dt / 4, dt_min)
                    continue
                rise = float(p.rigid.values[1]) - y0
                previous = float(committed["r"][1]) - y0
                lift = abs(rise - previous)
                if lift > max_rise_per_increment and dt > dt_min:
                    p.restore(committed)  # the lift grows like dt^2 from rest: aim at 0.8 of the cap
                    dt = max(dt * min(0.5, max(0.05, 0.8 * np.sqrt(max_rise_per_increment / lift))), dt_min)
                    continue
                outcome.newton_iterations += iterations
                zones = self.zone_forces()
                hit = self._event(event, rise, zones)
                if hit:
                    try:
                        t_event = self._locate(hit, event, index, t, dt, committed, y0, previous, rise, outcome)
                    except (NewtonFailure, RuntimeError, FloatingPointError):
                        if dt <= dt_min:
                            raise
                        p.restore(committed)  # locate it again within a shorter increment
                        dt = max(dt / 4, dt_min)
                        continue
                    outcome.before_event = committed
                    outcome.event, outcome.time = hit, float(self.schedule.start_times[index] + t_event)
                    if self.listeners:  # the state at the event closes the output
                        self.record(self.recorder.row(self.schedule.load(index, t_event, t_event - t), 0))
                    return outcome
                if self.listeners:  # an output row costs an assembly: only when someone listens
                    self.record(self.recorder.row(load, iterations))
                self.accept(load)
                t = end
                outcome.increments += 1
                entry = (float(load.time), rise, float(self.velocity[1]), *zones)
                outcome.trace.append(entry + ((monitor(),) if monitor else ()))
                if iterations <= 8:
                    dt = min(2 * dt, dt_max)
                if period and t in checks:
                    if np.abs((p.rigid.values - reference) * weights).max() < settle_tolerance:
                        outcome.settled = True
                        break
                    reference = p.rigid.values.copy()
        return outcome

    @staticmethod
    def _event(event: Event, rise: float, zones: np.ndarray) -> str | None:
        if event.rise > 0 and rise >= event.rise:
            return "risen"
        if event.open_zones and np.all(zones <= 1e-12):
            return "open"
        return None

    def _locate(self, hit, event, index, t, dt, committed, y0, rise0, rise1, outcome) -> float:
        """Time since the step began at which the event happens inside [t, t + dt]: the
        increment is re-solved from its start with shorter dt (the state is left there)."""
        p = self.problem

        def resolve_to(h):
            p.restore(committed)
            load = self.schedule.load(index, t + h, h)
            outcome.newton_iterations += self.solve(load)
            return float(p.rigid.values[1]) - y0, self.zone_forces()

        if hit == "risen":  # secant on the rise, which is linear in v1 * h within the increment
            lo, hi, f_lo, f_hi = 0.0, dt, rise0 - event.rise, rise1 - event.rise
            h, side = hi, 0
            for _ in range(40):  # regula falsi, Illinois variant
                h = lo + (hi - lo) * (-f_lo) / (f_hi - f_lo) if f_hi != f_lo else hi
                value = resolve_to(h)[0] - event.rise
                if abs(value) <= event.rise_tolerance * event.rise or hi - lo <= event.time_tolerance:
                    break
                if value < 0:
                    lo, f_lo = h, value
                    f_hi, side = (f_hi / 2 if side == -1 else f_hi), -1
                else:
                    hi, f_hi = h, value
                    f_lo, side = (f_lo / 2 if side == 1 else f_lo), 1
            return t + h
        lo, hi = 0.0, dt  # all zones open at hi, not at lo
        while hi - lo > event.time_tolerance:
            mid = (lo + hi) / 2
            rise, zones = resolve_to(mid)
            if self._event(Event(0.0, True), rise, zones):
                hi = mid
            else:
                lo = mid
        resolve_to(hi)
        return t + hi
