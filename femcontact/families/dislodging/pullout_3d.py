"""The 3-D pull-out (task 'pullout_3d' of kind "dislodging_methods"): quasi-static thresholds of
the wedged cylinder, by bisection: the force along its axis, the torque about the axis and the
torque across it (against the wedging moment), all in the one process that wedged it (a
checkpoint written on 2 ranks did not restore: the 3-D mesh was partitioned differently in the
next process); every probe streamed to probes_3d.csv and read back when the case is run again;
its 2-D estimates from the 3-D contact forces."""
import csv
import math
import time
from pathlib import Path

import numpy as np

from femcontact.families.dislodging.pull import (PULL_STEP, largest_held, one_dof_thresholds, quasi_static_probe,
                                                 wedged_simulation)
from femcontact.io import read_csv
from femcontact.problem.loading import Schedule


def contacts_on_axis(row: dict, axis: np.ndarray, dim: int) -> dict:
    """Normal and tangential (along the peg axis, positive out of the hole) forces on the peg
    (N) at A (block mouth on the -x side, normal perpendicular to the peg's side in the plane of
    the tilt) and B (the tip on the +x wall, normal -x). Vertical = y in 2-D, z in 3-D."""
    v = dim - 1
    a = np.array([axis[0], axis[v]])
    n_A = np.array([a[1], -a[0]])
    on_A = -np.array([row["contact_A_Fx"], row[f"contact_A_F{'xyz'[v]}"]])
    on_B = -np.array([row["contact_B_Fx"], row[f"contact_B_F{'xyz'[v]}"]])
    return {"N_A": float(on_A @ n_A), "T_A": float(on_A @ a), "N_B": float(-on_B[0]), "T_B": float(on_B[1])}


PROBE_COLUMNS = ["method", "magnitude", "holds", "goes", "newton_iterations", "residual_N", "moved_mm", "zone_A_N",
                 "zone_B_N", "reason", "wall_s"]
TWISTS_3D = {"continuous": "force (N) along the peg axis, out of the hole",
             "twist": "torque (N*mm) about the peg axis",
             "twist_across": "torque (N*mm) about the axis across the peg (perpendicular to it, in the plane of the "
                             "wedging moment's axis), against the wedging moment"}


class WedgedPeg3D:
    """The wedged 3-D peg (quasi-static, no inertia) and its quasi-static thresholds: a force
    along its axis, a torque about it and a torque across it. Every probe is appended to the
    CSV file `probes` as it is solved; probes already in it are read back, not solved again
    (so a case stopped by its time limit resumes where it stopped, after wedging again)."""

    def __init__(self, scene: dict, restart=None, checkpoint=None, probes=None):
        from mpi4py import MPI

        self.scene, self.settings = scene, scene["dislodging"]
        self.simulation, self.wedge_time = wedged_simulation(scene, restart, checkpoint)
        sim = self.simulation
        rigid = sim.problem.rigid
        self.wedged_row, self.wedged = sim.history[-1], sim.snapshot()
        self.axis = rigid_axis(rigid)
        self.across = across_axis(scene["steps"][0]["moment"], self.axis)
        self.tilt = rigid.tilt()
        self.contacts = contacts_on_axis(self.wedged_row, self.axis, 3)
        self.comm = MPI.COMM_WORLD
        self.held_states = {}  # method -> {magnitude: equilibrium held}, for `quasi_static_probe`
        self.probes = Path(probes) if probes else None
        known = []
        if self.probes and self.comm.rank == 0 and self.probes.is_file():
            known = read_csv(self.probes)
        self.known = {(row["method"], round(float(row["magnitude"]), 6)): (row["holds"] == "True", row.get("goes") == "True")
                      for row in self.comm.bcast(known, root=0)}  # -> (holds, goes)
        self.resumed = len(self.known)

    def direction(self, method: str) -> np.ndarray:
        """Unit vector of the force ('continuous') or torque of a method (global)."""
        return self.across if method == "twist_across" else self.axis

    def probe(self, magnitude: float, method: str) -> dict:
        """Does the wedge hold `magnitude` of `method` (TWISTS_3D) quasi-statically? Yes when its
        equilibrium (`quasi_static_probe`: exact Newton from the wedged state, or on from the
        largest magnitude held, or the peg let travel to rest) has both contact zones loaded and
        the peg moved by less than `rise` (mm: along the axis, or the rotation about the load's
        axis times the peg radius), the dynamic pull's event. Its row (PROBE_COLUMNS)."""
        from femcontact.solver.newton import BodyGone, NewtonFailure

        sim, s = self.simulation, self.settings
        start = time.perf_counter()
        pull = sim.scene["steps"][PULL_STEP]
        r0 = self.wedged["state"]["r"]
        direction = self.direction(method)
        load = None

        def load_at(value):
            nonlocal load
            vector = list(value * direction)
            pull.update(force=vector if method == "continuous" else [], moment=[] if method == "continuous" else vector,
                        amplitude="step", load_point="peg_top")
            sim.schedule = Schedule(sim.scene, sim.problem.rigid, sim.schedule.points)
            load = sim.schedule.load(PULL_STEP, pull["duration"], pull["duration"])
            load.motion = r0.copy()
            return load

        def moved(travel) -> float:  # mm along the axis, or the rotation about the load's axis times the radius
            if method == "continuous":
                return float(np.dot(travel[:3], self.axis))
            return float(np.dot(travel[3:], direction)) * self.scene["peg"]["width"] / 2

        held = self.held_states.setdefault(method, {})
        row = {"method": method, "magnitude": float(magnitude), "reason": "", "holds": False, "goes": False,
               "moved_mm": "", "zone_A_N": "", "zone_B_N": ""}
        try:
            row["newton_iterations"] = quasi_static_probe(sim, self.wedged, load_at, magnitude, held,
                                                          lambda travel: abs(moved(travel)) >= s["rise"])
            converged = True
        except NewtonFailure as failure:
            converged = False
            history = failure.history or [float("nan")]
            row.update(newton_iterations=len(history) - 1, residual_N=history[-1], goes=isinstance(failure, BodyGone),
                       reason=str(failure).split(";")[0])
        except (FloatingPointError, RuntimeError) as error:
            converged = False
            row.update(reason=type(error).__name__)
        if converged:  # (a failed solve leaves the wedged state)
            R_u, R_r, _ = sim.newton.current_residual(load)
            zones = sim.zone_forces()
            distance = moved(sim.problem.rigid.values - r0)
            holds = bool(np.all(zones > 0) and abs(distance) < s["rise"])
            row.update(residual_N=sim.newton.norm(R_u, R_r), moved_mm=distance, zone_A_N=float(zones[0]),
                       zone_B_N=float(zones[-1]), holds=holds, goes=not holds)
            if holds:
                held[magnitude] = sim.problem.state()
        row["wall_s"] = time.perf_counter() - start
        return row

    def holds(self, magnitude: float, method: str) -> bool:
        """`probe`, or its answer read back from the probes file; new probes are appended to it."""
        key = (method, round(magnitude, 6))
        if key not in self.known:
            row = self.probe(key[1], method)
            self.known[key] = row["holds"], row["goes"]
            if self.probes and self.comm.rank == 0:
                new = not self.probes.is_file()
                with open(self.probes, "a", newline="") as stream:
                    writer = csv.DictWriter(stream, fieldnames=PROBE_COLUMNS, extrasaction="ignore")
                    if new:
                        writer.writeheader()
                    writer.writerow(row)
        return self.known[key][0]

    def threshold(self, method: str, high: float) -> dict:
        """Largest magnitude the wedge holds (`largest_held` from the guess `high`, doubled at most
        4 times) to `tolerance` (N; torques: tolerance x the peg radius), and `goes_at`, the
        smallest magnitude probed under which the peg was seen to go (None: none was): between
        the two lie loads whose equilibrium was neither found nor shown not to exist."""
        tolerance = self.settings["tolerance"] * (self.scene["peg"]["width"] / 2 if method != "continuous" else 1.0)
        low, high, solves = largest_held(lambda magnitude: self.holds(magnitude, method), high, tolerance, doublings=4)
        gone = [magnitude for (name, magnitude), (_, goes) in self.known.items() if name == method and goes]
        return {"threshold": low, "bracket": high - low, "solves": solves, "goes_at": min(gone, default=None)}


def across_axis(wedging_moment, axis: np.ndarray) -> np.ndarray:
    """Unit axis across the peg (perpendicular to its `axis`) of the torque that turns it back
    out of its wedge: against the wedging moment (N*mm, global), as the 2-D twist."""
    m = -np.asarray(wedging_moment or [0.0, 0.0, 0.0], float)
    m = m - np.dot(m, axis) * axis
    if not np.linalg.norm(m) > 0:
        raise ValueError("the wedging moment has no component across the peg axis")
    return m / np.linalg.norm(m)


def rigid_axis(rigid) -> np.ndarray:
    """The peg axis (unit, global) at the current pose."""
    from femcontact.physics.rotation import rotation_numpy

    return rotation_numpy(rigid.split(rigid.values)[1]) @ rigid.Q0[:, -1]


PROBES_FILE = "probes_3d.csv"


def run_3d(scene: dict, case_dir: Path, checkpoint: bool, restart) -> dict:
    """Task 'pullout_3d' (or the 3-D wedging prefix): the wedged cylinder and its three
    quasi-static thresholds (TWISTS_3D), each probe streamed to `PROBES_FILE` in `case_dir`."""
    mu = scene["contact"]["mu"]
    start = time.perf_counter()
    wedge = WedgedPeg3D(scene, restart, Path(case_dir) / "checkpoint" if checkpoint else None,
                    probes=Path(case_dir) / PROBES_FILE)
    c = wedge.contacts
    metrics = {**{f"wedged_{k}": v for k, v in c.items()}, "tilt_deg": math.degrees(wedge.tilt),
               "sum_normal_N": c["N_A"] + c["N_B"], "wedge_time_s": wedge.wedge_time,
               **{f"one_dof_{k}_N": v for k, v in one_dof_thresholds(**c, tilt=wedge.tilt, mu=mu).items()}}
    info = {"dofs": wedge.simulation.dofs, "effects": list(scene["effects"]), "probes_resumed": wedge.resumed}
    if len(scene["steps"]) <= PULL_STEP:
        return {"metrics": metrics, "timings": {"wedge": wedge.wedge_time}, "info": info}
    friction, radius = mu * metrics["sum_normal_N"], scene["peg"]["width"] / 2
    start_pull = time.perf_counter()
    pull = wedge.threshold("continuous", 2 * metrics["one_dof_first_slip_N"])  # the 2-D pull-out: ~first slip
    metrics.update(threshold_force_N=pull["threshold"], bracket_N=pull["bracket"], pull_solves=pull["solves"],
                   goes_at_force_N=pull["goes_at"],
                   degree_of_wedging=pull["threshold"] / friction, pull_time_s=time.perf_counter() - start_pull)
    wedging = float(np.linalg.norm(scene["steps"][0]["moment"]))
    for method, prefix in (("twist", "twist"), ("twist_across", "across")):
        start_twist = time.perf_counter()
        twist = wedge.threshold(method, friction * radius)
        metrics.update({f"{prefix}_threshold_moment_Nmm": twist["threshold"], f"{prefix}_bracket_Nmm": twist["bracket"],
                        f"{prefix}_goes_at_Nmm": twist["goes_at"],
                        f"{prefix}_solves": twist["solves"],
                        f"{prefix}_over_friction_torque": twist["threshold"] / (friction * radius),
                        f"{prefix}_over_wedging_moment": twist["threshold"] / wedging,
                        f"{prefix}_time_s": time.perf_counter() - start_twist})
    return {"metrics": metrics, "timings": {"wedge": wedge.wedge_time, "total_case": time.perf_counter() - start},
            "info": info}
