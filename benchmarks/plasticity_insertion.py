"""`make plasticity_insertion`: how stiff may the compliant support be before the chamfer
crossing yields the hole?

The Whitney insertion (scenes/insertion_2d.toml: rigid peg d 10 with a lateral error of 0.6 mm
into a 1 mm, 45 deg chamfer of a hole D 10.05 in two steel blocks, mu 0.1) with `plasticity` on
the thesis' stainless 316 (210 MPa, 290 MPa at plastic strain 1), the gripper moved down 1.5 mm
(the chamfer crossing and the first contact in the bore) in 0.005 mm increments, fine enough to
resolve the chamfer's sharp force peak (it converges at first order in the increment: at the
scene's support 9.12, 10.61, 10.82, 10.92 N with 0.1, 0.02, 0.01, 0.005 mm). The support's
lateral and angular stiffnesses K_x and K_theta are scaled together (K_z stays axially rigid)
from the scene's 20 N/mm and 3000 N*mm/rad; per stiffness: the peak insertion force in the
chamfer phases, the largest contact force, the peak von Mises stress, and the peak PEEQ and the
plastic zone at the end of the chamfer crossing. A case that fails is recorded with its reason.

Writes results/plasticity_insertion/contact_size_H.md, .json and .png (H the contact element size).

    python -m benchmarks.plasticity_insertion [--contact-size 0.25]
"""
import argparse
import json
import time
from pathlib import Path

from mpi4py import MPI

from femcontact.families import load_scene
from femcontact.families.insertion.metrics import force_history
from femcontact.families.repository import SCENES
from femcontact.outputs.tables import markdown_table
from femcontact.solver.stepping import Simulation

OUT = Path("results/plasticity_insertion")
SCENE = SCENES / "insertion_2d.toml"
KX, KTHETA = 20.0, 3000.0
FACTORS = (1, 2, 3, 4, 5, 6, 8, 10, 30)
"""Multiples of the scene's K_x and K_theta."""
INCREMENTS = 300
"""Increments of the 1.5 mm crossing (0.005 mm each)."""
CROSSING = ["effects=['friction', 'plane_strain', 'compliant_support', 'plasticity']",
            "plasticity.hardening=[[0, 210], [1, 290]]", "steps.0.support_motion={y=-1.5}",
            "steps.0.stop={column='support_Fy', value=1000.0}"]


def crossing(factor: float, contact_size: float, increments: int = INCREMENTS) -> dict:
    """The chamfer crossing with the support `factor` times stiffer, the 1.5 mm in `increments`:
    a row of the sweep."""
    overrides = CROSSING + [f"support.kx={KX * factor}", f"support.ktheta={KTHETA * factor}",
                            f"mesh.contact_size={contact_size}", f"steps.0.increments={increments}"]
    simulation = Simulation(load_scene(SCENE, overrides), MPI.COMM_SELF)
    row = {"factor": factor, "kx": KX * factor, "ktheta": KTHETA * factor, "contact_size": contact_size}
    start = time.perf_counter()
    try:
        simulation.run()
        row["status"] = "ok"
    except Exception as error:  # a failed stiffness is a measurement, not the end of the sweep
        row["status"] = f"{type(error).__name__}: {str(error)[:120]}"
    row["wall_s"] = time.perf_counter() - start
    history = simulation.history
    if not history:
        return row
    curve = force_history(simulation.scene, history)
    chamfer = [i for i, phase in enumerate(curve["phase"]) if phase in ("chamfer", "edge")]
    end = history[chamfer[-1]] if chamfer else history[-1]
    row.update(dofs=simulation.dofs, rows=len(history),
               chamfer_peak_Fz=max((curve["Fz"][i] for i in chamfer), default=0.0),
               peak_contact_force=max(max(r["contact_A_force"], r["contact_B_force"]) for r in history),
               peak_von_mises=max(r["max_von_mises"] for r in history),
               peeq_after_chamfer=end["max_peeq"], zone_after_chamfer=end["plastic_zone"],
               peeq_end=history[-1]["max_peeq"], zone_end=history[-1]["plastic_zone"])
    return row


def page(rows: list[dict], contact_size: float, seconds: float) -> str:
    lines = ["# Insertion on stainless 316: support stiffness against plastic flow in the chamfer crossing", "",
             f"`python -m benchmarks.plasticity_insertion --contact-size {contact_size:g}`, "
             f"{seconds:.0f} s on one core. See docs/plasticity.md.", "",
             *markdown_table(["K_x (N/mm)", "K_theta (N mm/rad)", "chamfer peak Fz (N)", "peak contact force (N)",
                              "peak von Mises (MPa)", "PEEQ after chamfer", "plastic zone after chamfer (mm^2)",
                              "PEEQ at 1.5 mm", "status", "wall (s)"],
                             [[r["kx"], r["ktheta"], r.get("chamfer_peak_Fz"), r.get("peak_contact_force"),
                               r.get("peak_von_mises"), r.get("peeq_after_chamfer"), r.get("zone_after_chamfer"),
                               r.get("peeq_end"), r["status"], r["wall_s"]] for r in rows],
                             formats=["{:g}", "{:g}", "{:.2f}", "{:.2f}", "{:.0f}", "{:.2e}", "{:.2e}", "{:.2e}", None,
                                      "{:.0f}"])]
    found = onset(rows)
    if found:
        lines += ["", f"Plastic flow in the chamfer crossing starts between K_x = {found[0]:g} and {found[1]:g} N/mm "
                  "on this mesh."]
    return "\n".join(lines) + "\n"


def onset(rows: list[dict]) -> tuple[float, float] | None:
    """(the stiffest K_x without plastic flow, the softest with it) in the chamfer crossing, or None."""
    ok = [r for r in rows if r["status"] == "ok"]
    elastic = [r["kx"] for r in ok if r["peeq_after_chamfer"] == 0]
    plastic = [r["kx"] for r in ok if r["peeq_after_chamfer"] > 0]
    return (max(elastic), min(plastic)) if elastic and plastic else None


def plot(rows: list[dict], contact_size: float, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [r for r in rows if r["status"] == "ok"]
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2), sharex=True)
    kx = [r["kx"] for r in ok]
    left.loglog(kx, [r["peak_von_mises"] for r in ok], "o-", label="peak von Mises in the hole")
    left.axhline(210, color="tab:red", ls="--", lw=1, label="yield 210 MPa")
    left.set(xlabel="support K_x (N/mm; K_theta scaled with it)", ylabel="MPa", title="Peak stress, chamfer crossing")
    plastic = [r for r in ok if r["peeq_after_chamfer"] > 0]
    right.loglog([r["kx"] for r in plastic], [r["peeq_after_chamfer"] for r in plastic], "o-", color="tab:red",
                 label="peak PEEQ")
    right.loglog([r["kx"] for r in plastic], [r["zone_after_chamfer"] for r in plastic], "s--", color="tab:grey",
                 label="plastic zone (mm^2 per mm)")
    elastic = [r["kx"] for r in ok if r["peeq_after_chamfer"] == 0]
    if elastic:
        right.plot(elastic, [min(r["peeq_after_chamfer"] for r in plastic) / 3 if plastic else 1e-6] * len(elastic),
                   "x", color="tab:blue", label="elastic: PEEQ = 0")
    right.set(xlabel="support K_x (N/mm)", title=f"After the chamfer crossing (contact element {contact_size:g} mm)")
    found = onset(rows)
    for axis in (left, right):
        if found:
            axis.axvspan(*found, color="tab:orange", alpha=0.3, label=f"flow starts: K_x {found[0]:g}-{found[1]:g}")
        axis.legend(fontsize=8, loc="upper left")
    failed = [r for r in rows if r["status"] != "ok"]
    if failed:
        right.text(0.98, 0.02, "failed: K_x " + ", ".join(f"{r['kx']:g}" for r in failed), transform=right.transAxes,
                   ha="right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--contact-size", type=float, default=0.25, help="mesh.contact_size along the walls (mm)")
    contact_size = parser.parse_args().contact_size
    start = time.perf_counter()
    OUT.mkdir(parents=True, exist_ok=True)
    rows = []
    for factor in FACTORS:
        rows.append(crossing(factor, contact_size))
        print(rows[-1], flush=True)
    seconds = time.perf_counter() - start
    name = f"contact_size_{contact_size:g}"
    (OUT / f"{name}.json").write_text(json.dumps(rows, indent=1))
    (OUT / f"{name}.md").write_text(page(rows, contact_size, seconds))
    plot(rows, contact_size, OUT / f"{name}.png")
    print(f"results in {OUT / name}.md and .png ({seconds:.0f} s)")


if __name__ == "__main__":
    from femcontact.process import quiet_logging

    quiet_logging()
    main()
