"""GetFEM driver for the Hertz benchmarks, for `make bench` to time against.

    python benchmarks/getfem_hertz.py [--dim 2|3] --contact-size H [--degree 1|2] [--increments N] --json

The same problem and mesh as `femcontact hertz`, meshed by femcontact's own gmsh builder
(geometry.block: the same contact-zone size h_c, zone and grading):
- 2-D: plane strain block 100 x 50 (E = 200000 MPa, nu = 0.3, bottom held), a rigid cylinder
  R = 50 pressed with P = 500 N/mm;
- 3-D: the quarter x, y >= 0 of a block 100 x 100 x 50 (E = 200000 MPa, nu = 0.3, bottom
  held, u.n = 0 on the symmetry planes x = 0 and y = 0 by multipliers), a rigid sphere R = 50
  pressed with P = 2000 N (P / 4 on the quarter), h_c uniform on r <= 1.5 a;
under force control in N increments. GetFEM's formulation: Alart-Curnier augmented
Lagrangian on the top edge or face, the contact pressure p (>= 0, MPa) a Lagrange multiplier
of the displacement's degree there, and the indenter's vertical position d (mm) an unknown
balanced by the load F:

    sigma(u) : eps(v) - [p - r g]_+ n . v                              (block, top)
    (1/r) ([p - r g]_+ - p) q                                        (top)
    ([p - r g]_+ n_z + F / A) e                                      (top of measure A)

with g = |X + u - (0, .., R + d)| - R and n the indenter's outward normal, r = 10 E / h_c.
Prints one JSON object with the keys of `femcontact hertz --json`: dofs, newton_iterations,
a, p0, timings (s) and surface ([x, p] for every node of the top edge in 2-D, [r, p] with
r = sqrt(x^2 + y^2) for every node of the top face in 3-D). Needs GetFEM's Python interface
(Debian: python3-getfem); exits with status 3 and a message when it is not importable. Not
part of femcontact.
"""
import argparse
import json
import os
import sys
import tempfile
import time

START = time.perf_counter()
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))  # femcontact's geometry and data

from femcontact.references.hertz import BENCHMARK, BENCHMARK_3D, benchmark_half_width, benchmark_radius_3d  # noqa: E402

BLOCK = 100  # region of the block's cells (GetFEM merges regions of equal number)
QUARTER = 4  # the 3-D model is the quarter x, y >= 0


def problem(dim: int, contact_size: float) -> dict:
    """The benchmark's data and femcontact's scene keys its mesh builder reads."""
    if dim == 2:
        b = BENCHMARK
        a = benchmark_half_width()
        return {"load": b["P"], "R": b["R"], "E": b["E"], "nu": b["nu"], "a": a,
                "scene": {"dim": 2, "block": {"width": b["width"], "height": b["height"]},
                          "indenter": {"shape": "cylinder"},
                          "mesh": {"contact_size": contact_size, "contact_zone": max(2.5 * a, 4 * contact_size),
                                   "size_max": 8.0, "resolution": 1.0}}}
    b = BENCHMARK_3D
    a = benchmark_radius_3d()
    return {"load": b["P"] / QUARTER, "R": b["R"], "E": b["E"], "nu": b["nu"], "a": a,
            "scene": {"dim": 3, "block": {"width": b["width"], "depth": b["depth"], "height": b["height"],
                                          "symmetry": "quarter"},
                      "indenter": {"shape": "sphere"},
                      "mesh": {"contact_size": contact_size, "contact_zone": 1.5 * a, "size_max": 8.0,
                               "resolution": 1.0}}}


def mesh_file(scene: dict, path: str) -> dict:
    """Write femcontact's Hertz mesh (gmsh 2.2 format); its facet region numbers by name."""
    import gmsh

    from geometry import block, gmsh_tools

    gmsh_tools.start("hertz")
    names = block.generate(scene, block.sizes(scene))
    dim = scene["dim"]
    for group_dim, tag in gmsh.model.getPhysicalGroups(dim):  # GetFEM merges regions of equal number
        entities = gmsh.model.getEntitiesForPhysicalGroup(group_dim, tag)
        gmsh.model.removePhysicalGroups([(group_dim, tag)])
        gmsh.model.addPhysicalGroup(group_dim, list(entities), BLOCK)
    gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
    gmsh.write(path)
    return {**names["facets"], "symmetry": names["symmetry"]}


def solve(dim: int, contact_size: float, degree: int, increments: int) -> dict:
    import getfem as gf
    import numpy as np

    gf.util("trace level", 0)
    gf.util("warning level", 0)
    timings = {"startup": time.perf_counter() - START}
    start = time.perf_counter()
    data = problem(dim, contact_size)
    with tempfile.TemporaryDirectory() as directory:
        path = os.path.join(directory, "hertz.msh")
        regions = mesh_file(data["scene"], path)
        mesh = gf.Mesh("import", "gmsh", path)
    top, bottom = regions["top"], regions["bottom"]
    timings["mesh"] = time.perf_counter() - start

    start = time.perf_counter()
    E, nu, R, load = data["E"], data["nu"], data["R"], data["load"]
    simplex = "TRIANGLE" if dim == 2 else "TETRAHEDRON"
    # GetFEM's tetrahedral rules have degrees 1, 2, 3, 5, 6, 8: the stiffness's 2 (p - 1) exactly
    stiffness_rule, contact_rule = (2 * degree, 4 * degree) if dim == 2 else ({1: 1, 2: 2}[degree], {1: 5, 2: 8}[degree])
    mfu = gf.MeshFem(mesh, dim)
    mfu.set_classical_fem(degree)
    mfp = gf.MeshFem(mesh, 1)
    mfp.set_classical_fem(degree)
    mim = gf.MeshIm(mesh, gf.Integ(f"IM_{simplex}({stiffness_rule})"))
    mim_contact = gf.MeshIm(mesh, gf.Integ(f"IM_{simplex}({contact_rule})"))
    model = gf.Model("real")
    model.add_fem_variable("u", mfu)
    model.add_filtered_fem_variable("p", mfp, top)
    model.add_variable("d", 1)
    model.set_variable("d", [-1e-3 * contact_size])  # the indenter touches: Newton's first contact set
    lame_mu = E / (2 * (1 + nu))
    lame_lambda = E * nu / ((1 + nu) * (1 - 2 * nu))  # 3-D, and plane strain in 2-D
    model.add_initialized_data("lambda", [lame_lambda])
    model.add_initialized_data("mu", [lame_mu])
    model.add_isotropic_linearized_elasticity_brick(mim, "u", "lambda", "mu")
    model.add_Dirichlet_condition_with_simplification("u", bottom)
    for name in regions["symmetry"]:
        model.add_normal_Dirichlet_condition_with_multipliers(mim, "u", degree, regions[name])
    area = gf.asm("generic", mim_contact, 0, "1", top)
    model.add_initialized_data("r", [10 * E / contact_size])
    model.add_initialized_data("load", [0.0])
    axis = ";".join(["0"] * (dim - 1) + [f"{R!r}+d"])
    centre = f"(X+u-[{axis}])"
    gap = f"(Norm{centre}-{R!r})"
    pressure = f"pos_part(p-r*{gap})"
    model.add_nonlinear_term(mim_contact, f"-{pressure}*(Normalized{centre}.Test_u)", top)
    model.add_nonlinear_term(mim_contact, f"(1/r)*({pressure}-p)*Test_p", top)
    model.add_nonlinear_term(mim_contact, f"({pressure}*Normalized{centre}({dim})+load/{area!r})*Test_d", top)
    timings["forms"] = time.perf_counter() - start

    start = time.perf_counter()
    newton = []
    for k in range(1, increments + 1):
        model.set_variable("load", [load * k / increments])
        iterations = model.solve("max_res", 1e-9 * load, "max_iter", 40, "lsolver", "mumps")
        iterations = int(np.atleast_1d(iterations)[0])
        newton.append(iterations)
    timings["solve"] = time.perf_counter() - start

    start = time.perf_counter()
    dofs_p = mfp.basic_dof_on_region(top)
    nodes = mfp.basic_dof_nodes(dofs_p)
    x = nodes[0] if dim == 2 else np.hypot(nodes[0], nodes[1])
    # nodal pressure [p - r g]_+ (the multiplier p itself is its L2 projection on the surface,
    # which oscillates around zero outside the contact zone)
    p = model.interpolation(pressure, mfp, top)[dofs_p]
    order = np.argsort(x)
    surface = [[float(x[i]), float(p[i])] for i in order]
    timings["postprocess"] = time.perf_counter() - start
    timings["total"] = time.perf_counter() - START
    return {"code": "GetFEM", "dim": dim, "contact_size": contact_size, "degree": degree, "dofs": int(mfu.nbdof()),
            "newton_iterations": int(sum(newton)), "newton_per_increment": newton,
            "d": float(model.variable("d")[0]), "timings": timings, "surface": surface}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dim", type=int, default=2, choices=(2, 3))
    parser.add_argument("--contact-size", type=float, required=True, help="h_c (mm)")
    parser.add_argument("--degree", type=int, default=2, choices=(1, 2))
    parser.add_argument("--increments", type=int, default=2)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    try:
        import getfem  # noqa: F401  (is it installed?)
    except ImportError as error:
        print(f"GetFEM's Python interface is not importable ({error}); install python3-getfem", file=sys.stderr)
        return 3
    result = solve(args.dim, args.contact_size, args.degree, args.increments)
    print(json.dumps(result) if args.json else {k: v for k, v in result.items() if k != "surface"})
    return 0


if __name__ == "__main__":
    sys.exit(main())
