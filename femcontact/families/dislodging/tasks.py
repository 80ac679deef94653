"""One case of kind "dislodging_methods": the wedged peg, its degree of wedging, then its task.

- Degree of wedging of a wedged state: its quasi-static pull-out force P over mu times the sum of
  the residual normal forces, P / (mu (N_A + N_B)): 1 when the pull has to overcome the full
  friction of both contacts (a peg that only translates), less when the peg can pivot out of the
  wedge (task 'wedge': only this).
- task 'threshold': the threshold peak of a method (`methods.py`) by bisection;
- tasks 'optimise', 'optimise_peak': the pulse of least impulse or least peak force
  (`pulse_optimisation.py`);
- a 3-D scene: the pull-out along the axis and the twists about and across it (`pullout_3d.py`).
"""
import csv
import math
import time
from pathlib import Path

from femcontact.families.dislodging.methods import MethodPuller
from femcontact.families.dislodging.pull import PULL_STEP
from femcontact.families.dislodging.pulse_optimisation import optimise, optimise_peak, verify, verify_peak
from femcontact.families.dislodging.pullout_3d import run_3d


PULL_COLUMNS = ["case", "method", "phase", "magnitude_N", "peak_force_N", "pulse_hz", "duty", "shape", "dislodged",
                "event", "dislodge_time_s", "impulse_Ns", "applied_impulse_Ns", "objective_Ns", "increments",
                "newton_iterations", "settled", "wall_s"]


def run_case(scene: dict, case_dir: Path, checkpoint: bool = False, restart=None) -> dict:
    """One study case of kind "dislodging_methods" (see the module docstring)."""
    from mpi4py import MPI

    if scene["dim"] == 3:  # task 'pullout_3d', or its wedging prefix
        return run_3d(scene, case_dir, checkpoint, restart)
    case_dir, s, mu = Path(case_dir), scene["dislodging"], scene["contact"]["mu"]
    start = time.perf_counter()
    puller = MethodPuller(scene, restart, case_dir / "checkpoint" if checkpoint else None)
    c = puller.contacts
    pullout = puller.pullout["quasi_static_pullout_N"]
    friction = mu * (c["N_A"] + c["N_B"])
    metrics = {**{f"wedged_{k}": v for k, v in c.items()}, "sum_normal_N": c["N_A"] + c["N_B"],
               "tilt_deg": math.degrees(puller.tilt), "one_dof_first_slip_N": puller.one_dof["first_slip"],
               "one_dof_full_slide_N": puller.one_dof["full_slide"], **puller.pullout,
               "degree_of_wedging": pullout / friction,
               "degree_of_wedging_rotation_held": puller.pullout.get("quasi_static_pullout_N_rotation_held", 0.0) / friction,
               "wedge_time_s": puller.wedge_time, "pullout_time_s": puller.pullout_time}
    info = {"dofs": puller.simulation.dofs, "effects": list(scene["effects"])}
    rows = []
    if len(scene["steps"]) > PULL_STEP and s["task"] == "threshold":
        metrics.update(puller.threshold(s["method"], rows, s["pulse_hz"], s["duty"], s["shape"]))
    elif len(scene["steps"]) > PULL_STEP and s["task"] == "optimise":
        optimum = optimise(puller, rows)
        optimum.update(verify(scene, restart, optimum))
        metrics.update({f"optimum_{k}": v for k, v in optimum.items()})
        if MPI.COMM_WORLD.rank == 0:
            from femcontact.io import write_json_atomic

            write_json_atomic(case_dir / "optimum.json", optimum)
    elif len(scene["steps"]) > PULL_STEP and s["task"] == "optimise_peak":
        optimum = optimise_peak(puller, rows)
        optimum.update(verify_peak(scene, restart, optimum))
        metrics.update({f"optimum_{k}": v for k, v in optimum.items() if k != "all_evaluations"})
        if MPI.COMM_WORLD.rank == 0:
            from femcontact.io import write_json_atomic

            write_json_atomic(case_dir / "optimum_peak.json", optimum)
    if rows and MPI.COMM_WORLD.rank == 0:
        with open(case_dir / "pulls.csv", "w", newline="") as stream:
            writer = csv.DictWriter(stream, fieldnames=PULL_COLUMNS, extrasaction="ignore")
            writer.writeheader()
            writer.writerows(rows)
    metrics.update(pulls=len(rows), pull_wall_s=float(sum(row["wall_s"] for row in rows)))
    return {"metrics": metrics, "timings": {"wedge": puller.wedge_time, "total_case": time.perf_counter() - start},
            "info": info}
