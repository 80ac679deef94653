"""GetFEM driver for the Hertz benchmark (docs/references.md), for `make bench` to time against.

    python benchmarks/getfem_hertz.py --contact-size H [--degree 1|2] [--increments N] --json

The same problem and mesh as `femcontact hertz`: plane strain block 100 x 50 (E = 200000 MPa,
nu = 0.3, bottom held) meshed by femcontact's own gmsh builder (geometry.block, the same
contact-zone size h_c, zone and grading), a rigid cylinder R = 50 pressed with P = 500 N/mm
under force control in N increments. GetFEM's formulation: Alart-Curnier augmented
Lagrangian on the top edge, the contact pressure p (>= 0, MPa) a Lagrange multiplier of the
displacement's degree on that edge, and the cylinder's vertical position d (mm) an unknown
balanced by P:

    sigma(u) : eps(v) - [p - r g]_+ n . v                              (block, top edge)
    (1/r) ([p - r g]_+ - p) q                                        (top edge)
    ([p - r g]_+ n_y + P / L) e                                      (top edge of length L)

with g = |X + u - (0, R + d)| - R and n the cylinder's outward normal, r = 10 E / h_c.
Prints one JSON object with the keys of `femcontact hertz --json`: dofs, newton_iterations,
a, p0, timings (s) and surface ([x, p] for every node of the top edge). Needs GetFEM's
Python interface (Debian: python3-getfem); exits with status 3 and a message when it is
not importable. Not part of femcontact.
"""
import argparse
import json
import math
import os
import sys
import tempfile
import time

START = time.perf_counter()

P, R, E, NU, WIDTH, HEIGHT = 500.0, 50.0, 200000.0, 0.3, 100.0, 50.0
BOTTOM, TOP, BLOCK = 1, 3, 100  # regions: geometry.block's edge groups (bottom 1, right 2, top 3, left 4)
A = math.sqrt(4 * P * R / (math.pi * E / (1 - NU * NU)))  # 0.380567 mm


def mesh_file(contact_size: float, path: str) -> None:
    """Write the femcontact Hertz mesh (gmsh 2.2 format, physical groups named as femcontact's)."""
    import gmsh

    from geometry import block, gmsh_tools

    scene = {"dim": 2, "block": {"width": WIDTH, "height": HEIGHT}, "indenter": {"shape": "cylinder"},
             "mesh": {"contact_size": contact_size, "contact_zone": max(2.5 * A, 4 * contact_size),
                      "size_max": 8.0, "resolution": 1.0}}
    gmsh_tools.start("hertz")
    block.generate(scene, block.sizes(scene))
    for dim, tag in gmsh.model.getPhysicalGroups(2):  # GetFEM merges regions of equal number
        surfaces = gmsh.model.getEntitiesForPhysicalGroup(dim, tag)
        gmsh.model.removePhysicalGroups([(dim, tag)])
        gmsh.model.addPhysicalGroup(dim, list(surfaces), BLOCK)
    gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
    gmsh.write(path)


def solve(contact_size: float, degree: int, increments: int) -> dict:
    import getfem as gf
    import numpy as np

    gf.util("trace level", 0)
    gf.util("warning level", 0)
    timings = {"startup": time.perf_counter() - START}
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as directory:
        path = os.path.join(directory, "hertz.msh")
        mesh_file(contact_size, path)
        mesh = gf.Mesh("import", "gmsh", path)
    top, bottom = TOP, BOTTOM
    timings["mesh"] = time.perf_counter() - start

    start = time.perf_counter()
    mfu = gf.MeshFem(mesh, 2)
    mfu.set_classical_fem(degree)
    mfp = gf.MeshFem(mesh, 1)
    mfp.set_classical_fem(degree)
    mim = gf.MeshIm(mesh, gf.Integ(f"IM_TRIANGLE({2 * degree})"))  # exact for the stiffness
    mim_contact = gf.MeshIm(mesh, gf.Integ(f"IM_TRIANGLE({4 * degree})"))
    model = gf.Model("real")
    model.add_fem_variable("u", mfu)
    model.add_filtered_fem_variable("p", mfp, top)
    model.add_variable("d", 1)
    model.set_variable("d", [-1e-3 * contact_size])  # the cylinder touches: Newton's first contact set
    lame_mu = E / (2 * (1 + NU))
    lame_lambda = E * NU / ((1 + NU) * (1 - 2 * NU))  # plane strain
    model.add_initialized_data("lambda", [lame_lambda])
    model.add_initialized_data("mu", [lame_mu])
    model.add_isotropic_linearized_elasticity_brick(mim, "u", "lambda", "mu")
    model.add_Dirichlet_condition_with_simplification("u", bottom)
    length = gf.asm("generic", mim_contact, 0, "1", top)
    model.add_initialized_data("r", [10 * E / contact_size])
    model.add_initialized_data("load", [0.0])
    centre = f"(X+u-[0;{R!r}+d])"
    gap = f"(Norm{centre}-{R!r})"
    pressure = f"pos_part(p-r*{gap})"
    model.add_nonlinear_term(mim_contact, f"-{pressure}*(Normalized{centre}.Test_u)", top)
    model.add_nonlinear_term(mim_contact, f"(1/r)*({pressure}-p)*Test_p", top)
    model.add_nonlinear_term(mim_contact, f"({pressure}*Normalized{centre}(2)+load/{length!r})*Test_d", top)
    timings["forms"] = time.perf_counter() - start

    start = time.perf_counter()
    newton = []
    for k in range(1, increments + 1):
        model.set_variable("load", [P * k / increments])
        iterations = model.solve("max_res", 1e-9 * P, "max_iter", 40, "lsolver", "mumps")
        iterations = int(np.atleast_1d(iterations)[0])
        newton.append(iterations)
    timings["solve"] = time.perf_counter() - start

    start = time.perf_counter()
    dofs_p = mfp.basic_dof_on_region(top)
    x = mfp.basic_dof_nodes(dofs_p)[0]
    # nodal pressure [p - r g]_+ (the multiplier p itself is its L2 projection on the edge,
    # which oscillates around zero outside the contact zone)
    p = model.interpolation(pressure, mfp, top)[dofs_p]
    order = np.argsort(x)
    surface = [[float(x[i]), float(p[i])] for i in order]
    timings["postprocess"] = time.perf_counter() - start
    timings["total"] = time.perf_counter() - START
    return {"code": "GetFEM", "contact_size": contact_size, "degree": degree, "dofs": int(mfu.nbdof()),
            "newton_iterations": int(sum(newton)), "newton_per_increment": newton,
            "d": float(model.variable("d")[0]), "timings": timings, "surface": surface}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--contact-size", type=float, required=True, help="h_c (mm)")
    parser.add_argument("--degree", type=int, default=2, choices=(1, 2))
    parser.add_argument("--increments", type=int, default=2)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    try:
        import getfem  # noqa: F401
    except ImportError as error:
        print(f"GetFEM's Python interface is not importable ({error}); install python3-getfem", file=sys.stderr)
        return 3
    result = solve(args.contact_size, args.degree, args.increments)
    print(json.dumps(result) if args.json else {k: v for k, v in result.items() if k != "surface"})
    return 0


if __name__ == "__main__":
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    sys.exit(main())
