"""`make plasticity`: does the wedged state yield, what does plastic flow do to the force that
holds the peg, and does an edge radius make the peak stress a property of the parts?

1. Wedging (scenes/wedging_2d.toml) at the thesis depths l_d = 4, 5, 6 on meshes of
   resolution 0.5, 1, 2, elastic and with `plasticity` on the thesis' stainless 316 (210 MPa,
   290 MPa at plastic strain 1): the residual force R_A after release, the peak von Mises
   stress under load, the peak PEEQ and the plastic zone.
2. The peg's tip corner rounded (`peg.corner_radius` = 1 mm), the contact zones refined
   (`mesh.contact_size` 0.02 to 0.0025 mm), under the wedging push: the peak von Mises stress
   in block B (under the rounded corner) against block A (whose own mouth corner stays sharp),
   elastic, and the peak PEEQ and plastic zone with `plasticity`.
3. Cost: seconds per increment with and without `plasticity` (`bench.plasticity_costs`, the
   table `make bench` also writes).

Writes results/plasticity/plasticity.md, plasticity.json and plasticity.png.

    python -m benchmarks.plasticity
"""
import json
import time
from pathlib import Path

from dolfinx import fem
from mpi4py import MPI

from femcontact.families import load_scene
from femcontact.families.repository import SCENES
from femcontact.outputs.tables import markdown_table
from femcontact.solver.stepping import Simulation
from geometry.measures import cell_coordinates

from benchmarks import bench

OUT = Path("results/plasticity")
SCENE = SCENES / "wedging_2d.toml"
ELASTIC, PLASTIC = ["friction", "plane_strain"], ["friction", "plane_strain", "plasticity"]
THESIS_316 = "plasticity.hardening=[[0, 210], [1, 290]]"
CONTACT_SIZES = (0.02, 0.01, 0.005, 0.0025)


def run(overrides: list[str]) -> Simulation:
    simulation = Simulation(load_scene(SCENE, overrides + [THESIS_316]), MPI.COMM_SELF)
    simulation.run()
    return simulation


def wedging_rows() -> list[dict]:
    rows = []
    for depth in (4.0, 5.0, 6.0):
        for resolution in (0.5, 1.0, 2.0):
            row = {"l_d": depth, "resolution": resolution}
            for law, effects in (("elastic", ELASTIC), ("plastic", PLASTIC)):
                simulation = run([f"peg.insertion_depth={depth}", f"mesh.resolution={resolution}", f"effects={effects}"])
                end = simulation.step_end_rows()
                row[f"R_A_{law}"] = end["release"]["contact_A_force"]
                row[f"peak_von_mises_{law}"] = max(r["max_von_mises"] for r in simulation.history)
                if law == "plastic":
                    row["max_peeq"], row["plastic_zone"] = end["release"]["max_peeq"], end["release"]["plastic_zone"]
            row["R_A_change"] = row["R_A_plastic"] / row["R_A_elastic"] - 1
            rows.append(row)
            print(row, flush=True)
    return rows


def peak_by_block(simulation, name: str = "von_mises", value=None) -> dict:
    """Peak of a cellwise value (default the von Mises stress, MPa) in block A (x < 0) and block B
    (x > 0), as `{name}_A`, `{name}_B` (`peak_A`, `peak_B` for von Mises); in 3-D the block's
    halves beside contact A (the mouth edge) and contact B (the peg's tip rim). Global over the
    mesh's ranks."""
    p = simulation.problem
    W0 = fem.FunctionSpace(p.mesh, ("DG", 0))
    values = fem.Function(W0)
    values.interpolate(fem.Expression(p.von_mises if value is None else value, W0.element.interpolation_points()))
    x = cell_coordinates(p.mesh).mean(axis=1)[:, 0]
    local = values.x.array[: len(x)]
    prefix = "peak" if name == "von_mises" else name
    return {f"{prefix}_{side}": p.mesh.comm.allreduce(float(local[half].max(initial=0.0)), op=MPI.MAX)
            for side, half in (("A", x < 0), ("B", x > 0))}


def edge_radius_rows(radius: float = 1.0) -> list[dict]:
    push_only = "steps=[{name='load', increments=5, force=[-5.0, 1.0], load_point='peg_top'}]"
    rows = []
    for size in CONTACT_SIZES:
        row = {"corner_radius": radius, "contact_size": size}
        for law, effects in (("elastic", ELASTIC), ("plastic", PLASTIC)):
            simulation = run([f"peg.corner_radius={radius}", f"mesh.contact_size={size}", push_only, f"effects={effects}"])
            last = simulation.history[-1]
            row.update({f"{k}_{law}": v for k, v in peak_by_block(simulation).items()})
            row[f"R_A_{law}"] = last["contact_A_force"]
            if law == "plastic":
                row["max_peeq"], row["plastic_zone"] = last["max_peeq"], last["plastic_zone"]
        row["cells"] = simulation.problem.mesh.topology.index_map(2).size_global
        rows.append(row)
        print(row, flush=True)
    return rows


def page(wedging: list[dict], edges: list[dict], costs: list[dict], seconds: float) -> str:
    lines = ["# Plasticity: wedging on stainless 316, edge radius, cost", "",
             f"`make plasticity` (python -m benchmarks.plasticity), {seconds:.0f} s. "
             "See docs/plasticity.md.", "",
             "## Wedging at the thesis depths (push Fx = -5, Fy = 1 N, then release)", "",
             *markdown_table(["l_d", "resolution", "R_A elastic (N)", "R_A plastic (N)", "change",
                              "peak von Mises elastic / plastic (MPa)", "max PEEQ", "plastic zone (mm^2)"],
                             [[r["l_d"], r["resolution"], r["R_A_elastic"], r["R_A_plastic"], 100 * r["R_A_change"],
                               f"{r['peak_von_mises_elastic']:.0f} / {r['peak_von_mises_plastic']:.0f}", r["max_peeq"],
                               r["plastic_zone"]] for r in wedging],
                             formats=["{:g}", "{:g}", "{:.4f}", "{:.4f}", "{:+.2f} %", None, "{:.2e}", "{:.2e}"]),
             "", "## Peak stress under a rounded peg corner (corner_radius 1 mm, push only)", "",
             *markdown_table(["contact size (mm)", "cells", "peak von Mises B, rounded (MPa)",
                              "peak von Mises A, sharp (MPa)", "plastic: peak B / A (MPa)", "max PEEQ",
                              "plastic zone (mm^2)"],
                             [[r["contact_size"], r["cells"], r["peak_B_elastic"], r["peak_A_elastic"],
                               f"{r['peak_B_plastic']:.0f} / {r['peak_A_plastic']:.0f}", r["max_peeq"], r["plastic_zone"]]
                              for r in edges],
                             formats=["{:g}", None, "{:.0f}", "{:.0f}", None, "{:.2e}", "{:.2e}"]),
             "", "## Cost per increment (warm, fastest of 3, one core; as in make bench)", "",
             *bench.plasticity_cost_table(costs)]
    return "\n".join(lines) + "\n"


def plot(wedging: list[dict], edges: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    sizes = [r["contact_size"] for r in edges]
    left.loglog(sizes, [r["peak_A_elastic"] for r in edges], "o-", label="block A: sharp mouth corner, elastic")
    left.loglog(sizes, [r["peak_B_elastic"] for r in edges], "s-", label="block B: under the 1 mm peg radius, elastic")
    left.loglog(sizes, [r["peak_B_plastic"] for r in edges], "s--", label="block B, plastic")
    left.axhline(210, color="grey", lw=0.8, ls=":", label="yield 210 MPa")
    left.set(xlabel="contact element size (mm)", ylabel="peak von Mises (MPa)", title="Edge radius: the peak converges")
    left.invert_xaxis()  # refinement to the right
    left.legend(fontsize=8)
    for depth in (4.0, 5.0, 6.0):
        rows = [r for r in wedging if r["l_d"] == depth]
        right.plot([r["resolution"] for r in rows], [100 * r["R_A_change"] for r in rows], "o-", label=f"l_d = {depth:g}")
    right.axhline(0, color="grey", lw=0.8)
    right.set(xlabel="mesh resolution", ylabel="R_A plastic / elastic - 1 (%)", title="Residual force after release")
    right.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    start = time.perf_counter()
    OUT.mkdir(parents=True, exist_ok=True)
    wedging, edges, costs = wedging_rows(), edge_radius_rows(), bench.plasticity_costs()
    seconds = time.perf_counter() - start
    (OUT / "plasticity.json").write_text(json.dumps({"wedging": wedging, "edge_radius": edges, "cost": costs}, indent=1))
    (OUT / "plasticity.md").write_text(page(wedging, edges, costs, seconds))
    plot(wedging, edges, OUT / "plasticity.png")
    print(f"results in {OUT / 'plasticity.md'} and {OUT / 'plasticity.png'}")


if __name__ == "__main__":
    main()
