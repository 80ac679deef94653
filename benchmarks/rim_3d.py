"""`make rim_3d`: does a rounded rim on the 3-D peg make the peak stress a property of the parts?

The 3-D wedging scene (scenes/wedging_3d.toml: rigid cylinder d 40 in a round hole D 40.1 of
a steel block, mu 0.2, l_d 5) under its couple My = -1000 N*mm, with the peg's tip rim sharp
and rounded (`peg.corner_radius`, default 1 mm), on meshes whose contact zones (balls of
radius `mesh.contact_zone` = 1.5 mm around contacts A and B) have elements of h_c = 1, 0.5,
0.25, 0.125 mm, the rest of the block at mesh resolution 0.5. Per mesh and rim: the peak von
Mises stress at the end of the load in the block's half beside contact B (under the rim) and
beside contact A (the hole's own sharp mouth edge), the force at B and Newton's iterations;
then with `plasticity` (the thesis' 316) at h_c = 0.5, 0.25 and 0.125 mm: the peak equivalent
plastic strain beside B and A and the plastic volume.

Writes results/rim_3d/rim_3d.md and rim_3d.json. On 2 ranks:

    mpirun -n 2 python -m benchmarks.rim_3d [--radius 1.0] [--sizes 1 0.5 0.25 0.125]
                                            [--plastic-sizes 0.5 0.25 0.125]
"""
import argparse
import json
import time
from pathlib import Path

from mpi4py import MPI

from femcontact.families import load_scene
from femcontact.families.repository import SCENES
from femcontact.outputs.tables import markdown_table
from femcontact.solver.stepping import Simulation

from benchmarks.plasticity import THESIS_316, peak_by_block

OUT = Path("results/rim_3d")
SCENE = SCENES / "wedging_3d.toml"
RESOLUTION = 0.5
CONTACT_ZONE = 1.5  # mm
LOAD_ONLY = "steps=[{name='load', increments=5, moment=[0.0, -1000.0, 0.0]}]"


def case(radius: float, h_contact: float, plastic: bool = False) -> dict:
    """The loaded wedging peg with tip rim radius `radius` (mm; 0: sharp) and contact-zone
    elements of `h_contact` (mm), elastic or with `plasticity` (the thesis' 316), on
    MPI.COMM_WORLD."""
    overrides = [f"mesh.resolution={RESOLUTION}", f"mesh.contact_size={h_contact * RESOLUTION}",
                 f"mesh.contact_zone={CONTACT_ZONE}", f"peg.corner_radius={radius}", LOAD_ONLY]
    if plastic:
        overrides += ["effects=['friction', 'plasticity']", THESIS_316]
    start = time.perf_counter()
    simulation = Simulation(load_scene(SCENE, overrides), MPI.COMM_WORLD)
    simulation.run()
    last = simulation.history[-1]
    row = {"corner_radius": radius, "h_contact": h_contact, "plastic": plastic, "ranks": MPI.COMM_WORLD.size,
           "dofs": simulation.dofs, "newton": sum(row["newton_iterations"] for row in simulation.history),
           "force_B": last["contact_B_force"], "z_B": last["contact_B_z"], "tilt_deg": last["tilt_deg"],
           **peak_by_block(simulation)}
    if plastic:
        plasticity = next(c for c in simulation.problem.components if c.name == "plasticity")
        row.update(peak_by_block(simulation, "peeq", plasticity.cell_fields()["peeq"]))
        row["plastic_zone"] = last["plastic_zone"]
    return {**row, "seconds": time.perf_counter() - start}


def page(rows: list[dict], radius: float, seconds: float) -> str:
    elastic, plastic = [r for r in rows if not r.get("plastic")], [r for r in rows if r.get("plastic")]
    lines = [
        "# 3-D wedging: peak stress under a sharp and a rounded tip rim", "",
        f"`python -m benchmarks.rim_3d` on {rows[0]['ranks']} rank(s), {seconds:.0f} s. scenes/wedging_3d.toml "
        f"loaded (My = -1000 N*mm), mesh resolution {RESOLUTION}, contact zones of radius {CONTACT_ZONE} mm. "
        "B: the block's half under the peg's tip rim; A: the half with the hole's sharp mouth edge. "
        "See docs/wedging_3d.md."]
    if elastic:
        lines += ["", "## Peak von Mises at the end of the load", "", *markdown_table(
            ["h_c (mm)", "dofs", "sharp rim: peak von Mises B / A (MPa)", f"rim radius {radius:g} mm: B / A (MPa)",
             "force at B sharp / rounded (N)", "Newton sharp / rounded"],
            [[h, sharp["dofs"], f"{sharp['peak_B']:.0f} / {sharp['peak_A']:.0f}",
              f"{round_['peak_B']:.0f} / {round_['peak_A']:.0f}", f"{sharp['force_B']:.1f} / {round_['force_B']:.1f}",
              f"{sharp['newton']} / {round_['newton']}"] for h, sharp, round_ in pairs(elastic)],
            formats=["{:g}", None, None, None, None, None])]
    if plastic:
        lines += ["", "## With plasticity (316: 210 MPa, 290 MPa at plastic strain 1)", "", *markdown_table(
            ["h_c (mm)", "sharp rim: peak PEEQ B / A", f"rim radius {radius:g} mm: PEEQ B / A",
             "plastic zone sharp / rounded (mm^3)", "force at B sharp / rounded (N)", "Newton sharp / rounded"],
            [[h, f"{sharp['peeq_B']:.2e} / {sharp['peeq_A']:.2e}", f"{round_['peeq_B']:.2e} / {round_['peeq_A']:.2e}",
              f"{sharp['plastic_zone']:.2e} / {round_['plastic_zone']:.2e}",
              f"{sharp['force_B']:.1f} / {round_['force_B']:.1f}", f"{sharp['newton']} / {round_['newton']}"]
             for h, sharp, round_ in pairs(plastic)], formats=["{:g}", None, None, None, None, None])]
    return "\n".join(lines) + "\n"


def pairs(rows: list[dict]):
    """(h_c, sharp row, rounded row) per contact size, in the order run."""
    sizes = list(dict.fromkeys(row["h_contact"] for row in rows))
    for h in sizes:
        sharp, rounded = (next(r for r in rows if r["h_contact"] == h and (r["corner_radius"] > 0) == k)
                          for k in (False, True))
        yield h, sharp, rounded


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--radius", type=float, default=1.0, help="rim radius (mm)")
    parser.add_argument("--sizes", type=float, nargs="*", default=[1.0, 0.5, 0.25, 0.125],
                        help="element sizes h_c in the contact zones (mm)")
    parser.add_argument("--plastic-sizes", type=float, nargs="*", default=[0.5, 0.25, 0.125],
                        help="element sizes h_c (mm) of the runs with `plasticity`")
    args = parser.parse_args()
    start, rows = time.perf_counter(), []
    for h, plastic in [(h, False) for h in args.sizes] + [(h, True) for h in args.plastic_sizes]:
        for radius in (0.0, args.radius):
            rows.append(case(radius, h, plastic))
            if MPI.COMM_WORLD.rank == 0:
                print(rows[-1], flush=True)
    if MPI.COMM_WORLD.rank == 0:
        OUT.mkdir(parents=True, exist_ok=True)
        (OUT / "rim_3d.json").write_text(json.dumps(rows, indent=1))
        (OUT / "rim_3d.md").write_text(page(rows, args.radius, time.perf_counter() - start))
        print(f"results in {OUT / 'rim_3d.md'}")


if __name__ == "__main__":
    main()
