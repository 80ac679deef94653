"""Scene files: one simulation described in TOML, validated against a schema.

A contact scene (`kind = "contact"`, the finite-element contact solver) names its geometry,
materials, contact parameters, the physical `effects` it calls for, and its load steps.
`resolve_contact` returns the fully resolved scene (every default filled in); study families
add kinds of their own on top of it (femcontact.families.resolve_scene, which also reads scene
files). `case_id` hashes a resolved scene, so two files that differ only in key order or
formatting describe the same case.
"""
import hashlib
import json
import math
import tomllib
from pathlib import Path

from femcontact.physics.dofs import RIGID_DOFS
from femcontact.physics.support import stiffness_matrix
from femcontact.config.presets import PRESETS, apply_preset
from femcontact.errors import InputError
from femcontact.config.schema import Field, TableList, parse_assignment, set_key, validate
from geometry import snap_fit as snap_fit_geometry
from geometry.mesh_size import MAX_ELEMENTS

EFFECTS = ("friction", "inertia", "large_strain", "gravity", "plane_strain", "plane_stress", "compliant_support",
           "plasticity")


def deformable_body(scene: dict) -> str:
    """The deformable body's name (its key in `materials`): the rigid body's mate."""
    if scene["geometry"] == "snap_fit":
        return "spring"
    return {"peg": "hole", "hole": "peg", "indenter": "block"}[scene["rigid"]]


def friction_coefficient(scene: dict) -> float:
    """The Coulomb coefficient the scene simulates: `contact.mu` where it names `friction`, else 0."""
    return scene["contact"]["mu"] if "friction" in scene["effects"] else 0.0


def _material(E=193000.0, nu=0.27, density=8.05e-9, yield_stress=210.0) -> dict:
    """Defaults: stainless steel 316 as in the reference's wedging simulation."""
    return {
        "E": Field("float", E, "Young's modulus (MPa)", positive=True),
        "nu": Field("float", nu, "Poisson's ratio", min=0.0, max=0.4999),
        "density": Field("float", density, "density (t/mm^3)", min=0.0),
        "yield_stress": Field("float", yield_stress, "initial yield stress (MPa): the 'plasticity' effect's, "
                              "else only compared with the elastic von Mises stress (`yielded`)", positive=True),
    }


PEG = {
    "width": Field("float", doc="peg width d in 2-D, diameter in 3-D (mm)", positive=True),
    "length": Field("float", doc="peg length (mm)", positive=True),
    "insertion_depth": Field("float", doc="l_d: length of peg inside the hole, along the peg axis (mm)", min=0.0),
    "placement": Field("str", "two_point", "'two_point': tilt theta(l_d) touching both walls (less `gap`); "
                       "'centred': axis through the hole centre at `tilt`", choices=("two_point", "centred")),
    "tilt": Field("float", 0.0, "tilt (deg, counter-clockwise) for placement 'centred'", min=-89.0, max=89.0),
    "offset": Field("float", 0.0, "lateral offset (mm, along x) of the tip centre from the hole axis, "
                    "placement 'centred' (Whitney's lateral error)"),
    "gap": Field("float", 0.0, "horizontal gap (mm) left at both contact points for placement 'two_point'",
                 min=0.0),
    "chamfer_width": Field("float", 0.0, "peg-tip chamfer width across the axis (mm): a flat cut in 2-D, a cone "
                           "in 3-D, on a meshed or a rigid peg", min=0.0),
    "chamfer_angle": Field("float", 45.0, "peg-tip chamfer angle from the axis (deg)", min=1.0, max=89.0),
    "corner_radius": Field("float", 0.0, "edge radius of the rigid peg: its four corners in 2-D, its two rims (a "
                           "quarter torus each) in 3-D (mm); not with a chamfer, not on a meshed peg", min=0.0),
    "tip_contact": Field("bool", True, "false: the rigid peg's end faces take no contact from inside, a node "
                         "inside the peg is pushed out through its side (an entering peg: a wall node passed by "
                         "the tip corner cannot snag under the tip face); keep true if the peg can land on its tip"),
}

HOLE = {
    "width": Field("float", doc="hole width D in 2-D, diameter in 3-D (mm)", positive=True),
    "kind": Field("str", "two_blocks", "'two_blocks' (2-D: separate blocks A and B) or 'single' "
                  "(one U-shaped block in 2-D, a block with a cylindrical hole in 3-D)",
                  choices=("two_blocks", "single")),
    "depth": Field("float", 20.0, "hole depth (mm)", positive=True),
    "block_width": Field("float", 20.0, "width of each block beside the hole (mm)", positive=True),
    "bottom_thickness": Field("float", 10.0, "material below the hole bottom, 'single' only (mm)", positive=True),
    "chamfer_width": Field("float", 0.0, "hole-mouth chamfer width (mm); a meshed hole only (rigid = 'peg')",
                           min=0.0),
    "chamfer_angle": Field("float", 45.0, "hole-mouth chamfer angle from the axis (deg)", min=1.0, max=89.0),
    "support": Field("str", "outer", "fixed edge/face: 'outer' sides or 'bottom'", choices=("outer", "bottom")),
}

BLOCK = {
    "width": Field("float", 100.0, "block width in x (mm)", positive=True),
    "height": Field("float", 50.0, "block height in y (2-D) or z (3-D) (mm); top face at 0", positive=True),
    "depth": Field("float", 100.0, "block depth in y, 3-D only (mm)", positive=True),
    "symmetry": Field("str", "none", "'quarter' (3-D): mesh the quarter x >= 0, y >= 0 of the block, with symmetry "
                      "planes x = 0 and y = 0 (the indenter held to its axis; forces and reactions are the "
                      "quarter's)", choices=("none", "quarter")),
}

INDENTER = {
    "shape": Field("str", "cylinder", "rigid indenter: 'cylinder' (disc in 2-D), 'sphere' (3-D) or 'flat' "
                   "(a rigid plate)", choices=("cylinder", "sphere", "flat")),
    "radius": Field("float", 50.0, "cylinder or sphere radius (mm)", positive=True),
    "width": Field("float", 20.0, "flat indenter width (mm)", positive=True),
}

PIN = {
    "width": Field("float", 2.0, "pin width 2w: twice the shank radius (mm)", positive=True),
    "length": Field("float", 6.0, "pin length, nose tip to top (mm)", positive=True),
    "nose": Field("str", "taper", "nose shape: 'taper' (flat), 'convex' or 'concave' (circular arcs through the "
                  "taper's end points, tangent to the shank / to the axis), 'points' (`nose_points`)",
                  choices=("taper", "convex", "concave", "points")),
    "nose_angle": Field("float", 30.0, "taper half-angle measured from the insertion axis (deg); for the arcs the "
                        "angle of their chord", min=1.0, max=89.0),
    "nose_length": Field("float", 1.0, "axial length H of the nose (mm); with `nose_angle` it sets the tip radius "
                         "w - H tan(angle)", positive=True),
    "nose_points": Field("any", [], "nose = 'points': [[r, z], ...] (mm) from the tip (z = 0) to the shoulder "
                         "(r = width / 2), z increasing, r not decreasing", check=snap_fit_geometry.check_points),
    "start_gap": Field("float", 0.05, "axial gap (mm) between the nose and the spring apex at the start; the "
                       "insertion depth is the pin's travel less this gap", min=0.0),
}

SPRING = {
    "count": Field("int", 1, "contact springs: 1 (on the +x side) or 2 (mirrored)", choices=(1, 2)),
    "length": Field("float", 5.0, "cantilever length L, root to free end (mm)", positive=True),
    "thickness": Field("float", 0.3, "cantilever thickness h in the plane of bending (mm)", positive=True),
    "width": Field("float", 1.0, "out-of-plane width of spring and pin (mm): the plane-stress thickness; the 2-D "
                   "history is per mm of width, the snap-fit metrics (N) are multiplied by it; 3-D: the spring's "
                   "width, meshed (the pin is a blade without ends)", positive=True),
    "pad_height": Field("float", 0.3, "how far the contact pad at the free end reaches in from the spring (mm)",
                        positive=True),
    "interference": Field("float", 0.15, "lateral overlap of the pad's apex with the pin's shank (mm): the spring's "
                          "deflection at full insertion (a negative preload gap)", positive=True),
}

MESH = {
    "resolution": Field("float", 1.0, "global refinement knob: every mesh size is divided by it", positive=True),
    "contact_size": Field("float", 0.0, "element size in the contact zones (mm); 0 = automatic", min=0.0),
    "size_max": Field("float", 0.0, "largest element size (mm); 0 = automatic", min=0.0),
    "contact_zone": Field("float", 0.0, "half-length of each fine contact zone (mm), independent of "
                          "`resolution`; 0 = automatic (see docs/geometry.md)", min=0.0),
    "degree": Field("int", 1, "Lagrange degree of the displacement", choices=(1, 2)),
    "geometry_order": Field("int", 1, "order of the elements' geometry: 2 = quadratic (curved) elements whose "
                            "edge midpoints lie on the curved surfaces (a hole's cylinder and cone to within "
                            "h^3); needs mesh.degree = 2", choices=(1, 2)),
    "max_elements": Field("int", MAX_ELEMENTS, "largest estimated number of elements a run may mesh: a guard "
                          "against a mistyped size; raise it on purpose for a large mesh (3-D wedging at 4.8 million "
                          "estimated elements, 1.03M unknowns: 3.7 GB on one rank with the iterative solver, "
                          "docs/bench.md)", min=1),
}

CONTACT = {
    "mu": Field("float", 0.2, "Coulomb friction coefficient (used with the 'friction' effect)", min=0.0),
    "method": Field("str", "nitsche", "'nitsche' (consistent) or 'penalty' (less accurate: penetration ~ p/gamma)",
                    choices=("nitsche", "penalty")),
    "gamma": Field("float", 10.0, "normal parameter: gamma_N = gamma * E / h (dimensionless)", positive=True),
    "gamma_t": Field("float", 0.0, "tangential parameter gamma_T = gamma_t * E / h; 0 = same as gamma", min=0.0),
    "theta": Field("float", 0.0, "Nitsche variant: 1 symmetric, 0 skew-less, -1 skew-symmetric",
                   choices=(-1.0, 0.0, 1.0)),
    "surface": Field("str", "facets", "where the contact is measured in 3-D: 'facets' (the mesh's flat "
                     "facets, at their nodes) or 'exact' (a round hole's wall and chamfer facets moved onto the "
                     "exact cylinder and cone, at the facets' vertices and edge midpoints, with P2 also their "
                     "centroids; docs/wedging_3d.md)",
                     choices=("facets", "exact")),
    "normal": Field("str", "body", "direction of the contact force: 'body' (the rigid body's surface normal at "
                    "each contact point) or 'wall' (the deformable wall's normal where the wall is smooth; at its "
                    "edges the body's turned into the directions between the two faces' normals; the body's where "
                    "the two lie more than 45 deg apart: a rounded rim or a sharp edge pressing a smooth wall "
                    "pushes along the wall's normal, whichever contact points see it; docs/wedging_3d.md)",
                    choices=("body", "wall")),
}

MAX_INCREMENTS = 100_000
"""Increments of all steps of a scene together (each a Newton solve and a row of history.csv)."""

STEP = {
    "name": Field("str", "step", "step name"),
    "duration": Field("float", 1.0, "step duration (s)", positive=True),
    "increments": Field("int", 10, f"number of increments (all steps together at most {MAX_INCREMENTS}); a "
                        "dislodging scene's pull and observe steps take theirs from `dislodging.dt_max`",
                        min=1),
    "force": Field("floats", [], "force on the rigid body at `load_point` at the end of the step (N), [Fx, Fy(, Fz)]"),
    "moment": Field("floats", [], "moment on the rigid body (N*mm): Mz in 2-D, [Mx, My, Mz] in 3-D"),
    "load_point": Field("str", "peg_top", "named point where the force acts (e.g. peg_top, contact_A, peg_tip)"),
    "amplitude": Field("str", "ramp", "'ramp': linear from the previous step's value; 'step': at once; "
                       "'pulse': the value times a pulse train", choices=("ramp", "step", "pulse")),
    "pulse": {
        "frequency": Field("float", 10.0, "pulse frequency (Hz)", positive=True),
        "duty": Field("float", 1.0, "fraction of each period the pulse lasts", positive=True, max=1.0),
        "shape": Field("str", "triangle", "pulse shape", choices=("triangle", "square", "haversine")),
    },
    "motion": {name: Field("float", 0.0, "prescribed rigid-body displacement (mm) or rotation (rad) at the "
                           "end of the step, for dofs set 'prescribed'") for name in RIGID_DOFS[3]},
    "stop": {
        "column": Field("str", "", "end the run when this history column (e.g. support_Fy) exceeds `value` in "
                        "magnitude after an increment of this step; '' = never"),
        "value": Field("float", 0.0, "threshold of `column` (its units)", min=0.0),
    },
    "support_motion": {name: Field("float", 0.0, "with 'compliant_support': the gripper's displacement (mm) or "
                                   "rotation (rad) at the end of the step, from its start") for name in RIGID_DOFS[3]},
}

SUPPORT = {
    "model": Field("str", "springs", "'springs' (kx, kz, ktheta, ktorsion), 'matrix' (`stiffness`) or 'rcc' "
                   "(the RCC design formula, `rcc`)", choices=("springs", "matrix", "rcc")),
    "compliance_centre": Field("float", 0.0, "L_g: compliance centre above the peg tip, on its axis (mm)"),
    "kx": Field("float", 10.0, "lateral stiffness (N/mm; 3-D: x and y)", positive=True),
    "kz": Field("float", 1e5, "axial stiffness along the hole axis (N/mm)", positive=True),
    "ktheta": Field("float", 5e4, "angular stiffness about the out-of-plane axis (2-D), about x and y "
                    "(3-D) (N*mm/rad)", positive=True),
    "ktorsion": Field("float", 5e4, "torsional stiffness about the hole axis, 3-D (N*mm/rad)", positive=True),
    "stiffness": Field("floats", [], "model 'matrix': K row by row, 3x3 (x, y, rz) in 2-D, 6x6 (x, y, z, rx, "
                       "ry, rz) in 3-D (N/mm, N, N*mm/rad), global frame"),
    "rcc": {
        "b": Field("float", 50.0, "RCC base length b (mm)", positive=True),
        "peg_length": Field("float", 50.0, "RCC design peg length L (mm): places its centre at the design tip",
                            min=0.0),
        "theta_l": Field("float", 70.0, "RCC link tilt theta_L (deg)",
                         check=lambda v: None if 0.0 < v < 90.0 else "must lie in (0, 90)"),
        "k": Field("float", 200.0, "RCC link stiffness (N/mm)", positive=True),
    },
}

SOLVER = {
    "max_iterations": Field("int", 40, "Newton iterations per solve (one whose |R| has stopped moving stops "
                            "sooner: docs/stability.md, 'A Newton solve that stalls'). An increment whose plain "
                            "solve fails is solved again along the contact stabilisation's continuation, up to one "
                            "solve per stabilisation level, each within this limit: history.csv's newton_iterations "
                            "is the sum over the solves that led to the converged increment, so it can exceed this "
                            "value",
                            min=1),
    "rtol": Field("float", 1e-9, "relative residual tolerance", positive=True),
    "atol": Field("float", 1e-6, "absolute residual tolerance (N); the round-off floor of the contact "
                  "residual is about eps * |x| * gamma E / h, 1e-8 to 3e-7 N for the default wedging mesh",
                  positive=True),
    "max_cuts": Field("int", 8, "times an increment may be halved after a Newton failure", min=0),
    "line_search": Field("bool", True, "line search: the full step if the residual norm falls, else the "
                         "root of R.d or backtracking"),
    "curved_step": Field("bool", False, "when a full Newton step does not lower |R|, try first a step along a "
                         "path that follows the residual's curvature (one more residual and one solve): a rigid "
                         "body sliding a curved surface (a rounded rim) over contact nodes stays on it"),
    "contact_update": Field("bool", True, "where the bulk stiffness does not depend on the state (small strain), "
                            "factor it once and add the contact's few rows by a low-rank update (Woodbury); "
                            "off: factor the whole Jacobian every Newton iteration"),
    "linear": Field("str", "auto", "the linear solver: 'direct' (MUMPS LU; with `contact_update`, the bulk "
                    "factored once), 'iterative' (GMRES preconditioned by algebraic multigrid, a residual 1e-6 of "
                    "the right-hand side's; memory about linear in the unknowns) or 'auto' (iterative from 300,000 "
                    "unknowns, where the direct solver's memory outgrows a workstation's; docs/bench.md)",
                    choices=("auto", "direct", "iterative")),
    "petsc_options": Field("any", {}, "PETSc options for the linear solver (prefix-free)",
                           check=lambda v: None if isinstance(v, dict) else "must be a table"),
}

DYNAMICS = {
    "newmark_beta": Field("float", 0.3025, "Newmark beta (0.25: no numerical damping)", positive=True, max=0.5),
    "newmark_gamma": Field("float", 0.6, "Newmark gamma (0.5: no numerical damping)", min=0.5, max=1.0),
    "deformable_inertia": Field("bool", False, "with 'inertia': also the deformable body's mass (else the rigid body only)"),
    "gravity": Field("float", 9810.0, "gravitational acceleration for the 'gravity' effect (mm/s^2)", min=0.0),
}


def _hardening_problem(table) -> str | None:
    """Why a hardening table [[plastic strain, yield stress], ...] is unusable, or None."""
    if table == []:
        return None
    if not isinstance(table, list) or not all(isinstance(row, list) and len(row) == 2 for row in table):
        return "expected [[plastic strain, yield stress (MPa)], ...]"
    numbers = [v for row in table for v in row]
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in numbers):
        return "expected finite numbers"
    strains, stresses = [row[0] for row in table], [row[1] for row in table]
    if strains[0] != 0 or any(b <= a for a, b in zip(strains, strains[1:])):
        return "plastic strains must start at 0 and increase"
    if stresses[0] <= 0 or any(b < a for a, b in zip(stresses, stresses[1:])):
        return "yield stresses must be > 0 and not fall (no softening)"
    return None


PLASTICITY = {
    "hardening": Field("any", [], "isotropic hardening of the 'plasticity' effect: [[plastic strain, yield stress "
                       "(MPa)], ...], piecewise linear, its last slope continued; the first row [0, "
                       "materials.<body>.yield_stress]. Empty: linear with `hardening_modulus`",
                       check=_hardening_problem),
    "hardening_modulus": Field("float", 0.0, "slope of the yield stress over the equivalent plastic strain (MPa) "
                               "when `hardening` is empty; 0 = perfectly plastic", min=0.0),
}

OUTPUTS = {
    "fields": Field("bool", False, "write a ParaView time series, one frame per converged increment: fields.xdmf "
                    "(displacement, von Mises, stress, contact pressure, tangential traction, contact status, "
                    "slip since the step began, gap) and rigid.xdmf (the rigid body's outline or surface)"),
    "every": Field("int", 1, "with `fields`: write every N-th increment and the last of each step", min=1),
}


def contact_schema(dim: int, geometry: str) -> dict:
    """Schema of a contact scene for the given dimension and geometry."""
    schema = {
        "kind": Field("str", "contact", "'contact': the finite-element contact solver (study families add kinds "
                      "of their own, below)", choices=("contact",)),
        "accuracy": Field("str", "custom", "preset of mesh and solver keys the scene leaves unset "
                          "(docs/accuracy.md): 'fast', 'balanced', 'accurate', or 'custom' (none)",
                          choices=tuple(PRESETS)),
        "name": Field("str", "scene", "scene name"),
        "dim": Field("int", 2, "spatial dimension", choices=(2, 3)),
        "geometry": Field("str", "peg_in_hole", "'peg_in_hole', 'block' (a block under a rigid indenter) or "
                          "'snap_fit' (a rigid pin between cantilever contact springs)",
                          choices=("peg_in_hole", "block", "snap_fit")),
        "rigid": Field("str", "indenter" if geometry == "block" else "peg", "the rigid body",
                       choices={"peg_in_hole": ("peg", "hole"), "block": ("indenter",), "snap_fit": ("peg",)}[geometry]),
        "effects": Field("strs", ["plane_strain"] if dim == 2 else [], "physics the scene calls for", choices=EFFECTS),
        "mesh": MESH,
        "contact": CONTACT,
        "rigid_body": {
            "dofs": {name: Field("str", "free", "'free' (driven by loads), 'held' or 'prescribed' (by steps.motion)",
                                 choices=("free", "held", "prescribed")) for name in RIGID_DOFS[dim]},
            "mass": Field("float", 0.0, "rigid body mass (t); 0 = from its geometry and density", min=0.0),
        },
        "steps": TableList(STEP, "load steps, in order"),
        "dynamics": DYNAMICS,
        "solver": SOLVER,
        "plasticity": PLASTICITY,
        "outputs": OUTPUTS,
    }
    if geometry == "peg_in_hole":
        hole = dict(HOLE)
        if dim == 3:
            hole["kind"] = Field("str", "single", HOLE["kind"].doc, choices=("single",))
        schema.update(peg=PEG, hole=hole, support=SUPPORT, materials={"peg": _material(), "hole": _material()})
    elif geometry == "snap_fit":
        schema.update(peg=PIN, spring=SPRING, materials={"peg": _material(), "spring": _material()})
    else:
        schema.update(block=BLOCK, indenter=INDENTER, materials={"block": _material(), "indenter": _material()})
        step = {**STEP, "load_point": Field("str", "indenter", "named point where the force acts: 'indenter' "
                                            "(its reference point), 'contact' or 'reference'")}
        schema["steps"] = TableList(step, schema["steps"].doc)
    return schema


def check_contact(scene: dict) -> None:
    dim, effects = scene["dim"], scene["effects"]
    problems = []
    if "plane_strain" in effects and "plane_stress" in effects:
        problems.append(f"effects = {effects}: 'plane_strain' and 'plane_stress' exclude each other")
    if dim == 3 and {"plane_strain", "plane_stress"} & set(effects):
        problems.append(f"effects = {effects}: plane_strain/plane_stress are 2-D effects (dim = 3)")
    if "plasticity" in effects and "large_strain" in effects:
        problems.append(f"effects = {effects}: 'plasticity' is small-strain (drop 'large_strain')")
    round_hole = (dim, scene["geometry"], scene.get("rigid")) == (3, "peg_in_hole", "peg")
    if scene["contact"]["surface"] == "exact" and not round_hole:
        problems.append(f"contact.surface = 'exact': for the round hole of a 3-D peg_in_hole scene with a rigid peg "
                        f"(dim = {dim}, geometry = {scene['geometry']!r}, rigid = {scene.get('rigid')!r})")
    if scene["mesh"]["geometry_order"] > scene["mesh"]["degree"]:
        problems.append(f"mesh.geometry_order = {scene['mesh']['geometry_order']}: curved elements need a "
                        f"displacement of the same degree (mesh.degree = {scene['mesh']['degree']}; set it to 2)")
    table, body = scene["plasticity"]["hardening"], deformable_body(scene)
    if "plasticity" in effects and table and table[0][1] != scene["materials"][body]["yield_stress"]:
        problems.append(f"plasticity.hardening = {table}: its first yield stress must be "
                        f"materials.{body}.yield_stress = {scene['materials'][body]['yield_stress']}")
    moment_length = 1 if dim == 2 else 3
    if not scene["steps"]:
        problems.append("steps = []: a contact scene needs at least one [[steps]] table")
    names = [step["name"] for step in scene["steps"]]
    for i, name in enumerate(names):
        if name in names[:i]:
            problems.append(f"steps[{i}].name = {name!r}: also the name of steps[{names.index(name)}] "
                            "(step names key the metrics, they must differ)")
    problems += petsc_option_problems(scene["solver"]["petsc_options"])
    for i, step in enumerate(scene["steps"]):
        if step["force"] and len(step["force"]) != dim:
            problems.append(f"steps[{i}].force = {step['force']}: expected {dim} components")
        if step["moment"] and len(step["moment"]) != moment_length:
            problems.append(f"steps[{i}].moment = {step['moment']}: expected {moment_length} component(s)")
        for name, value in step["motion"].items():
            if value and scene["rigid_body"]["dofs"].get(name) != "prescribed":
                problems.append(f"steps[{i}].motion.{name} = {value}: rigid_body.dofs.{name} is not 'prescribed'")
        for name, value in step["support_motion"].items():
            if value and "compliant_support" not in effects:
                problems.append(f"steps[{i}].support_motion.{name} = {value}: needs the 'compliant_support' effect")
            elif value and name not in RIGID_DOFS[dim]:
                problems.append(f"steps[{i}].support_motion.{name} = {value}: not a {dim}-D dof "
                                f"({', '.join(RIGID_DOFS[dim])})")
        if step["amplitude"] == "pulse" and any(step["support_motion"].values()):
            problems.append(f"steps[{i}].support_motion: a 'pulse' step cannot move the gripper (use 'ramp' or 'step')")
    if scene["geometry"] == "block":
        problems += _block_problems(scene)
    support = scene.get("support")  # peg-in-hole scenes
    if support and support["stiffness"] and support["model"] != "matrix":
        problems.append(f"support.stiffness = {support['stiffness']}: read only with support.model = 'matrix' "
                        f"(support.model = {support['model']!r})")
    if "compliant_support" in effects and (scene.get("rigid") != "peg" or scene["geometry"] != "peg_in_hole"):
        problems.append(f"effects = {effects}: 'compliant_support' holds a rigid peg in a hole, "
                        "set geometry = 'peg_in_hole' and rigid = 'peg'")
    total = sum(step["increments"] for step in scene["steps"])
    if total > MAX_INCREMENTS:
        counts = ", ".join(f"steps[{i}].increments = {step['increments']}" for i, step in enumerate(scene["steps"])
                           if step["increments"] > MAX_INCREMENTS // 10)
        problems.append(f"{counts}: {total} increments in all, at most {MAX_INCREMENTS} (each a Newton solve and "
                        "a row of history.csv)")
    if problems:
        raise InputError("invalid scene:\n  " + "\n  ".join(problems) if len(problems) > 1 else problems[0])
    if "compliant_support" in effects:
        stiffness_matrix(scene)  # 'matrix': its size, symmetry and positive definiteness
    if scene["geometry"] == "peg_in_hole":
        from geometry.placement import check_peg_in_hole

        check_peg_in_hole(scene)
    if scene["geometry"] == "snap_fit":
        if scene["peg"]["nose"] == "points" and not scene["peg"]["nose_points"]:
            raise InputError("peg.nose_points: missing (required for peg.nose = 'points')")
        snap_fit_geometry.layout(scene)  # refuses a spring that cannot meet the nose
    from geometry.model import check_mesh, points

    known = sorted([*points(scene), "reference"])
    for i, step in enumerate(scene["steps"]):
        if step["load_point"] not in known:
            raise InputError(f"steps[{i}].load_point = {step['load_point']!r}: unknown point, expected one of "
                             + ", ".join(known))
    check_mesh(scene)  # an element-count estimate: a mesh too large or too coarse is refused before gmsh runs


def _block_problems(scene: dict) -> list[str]:
    """A sphere is a 3-D indenter; a quarter model is 3-D, its indenter held to the z axis and
    loaded along it."""
    problems = []
    if scene["indenter"]["shape"] == "sphere" and scene["dim"] != 3:
        problems.append("indenter.shape = 'sphere': a 3-D indenter (dim = 2; use 'cylinder')")
    if scene["block"]["symmetry"] != "quarter":
        return problems
    if scene["dim"] != 3:
        return problems + ["block.symmetry = 'quarter': a 3-D model (dim = 2)"]
    for name in ("x", "y", "rx", "ry", "rz"):
        if scene["rigid_body"]["dofs"][name] != "held":
            problems.append(f"rigid_body.dofs.{name} = {scene['rigid_body']['dofs'][name]!r}: block.symmetry = "
                            "'quarter' holds the indenter to the z axis, set it 'held'")
    for i, step in enumerate(scene["steps"]):
        if any(step["force"][:2]) or any(step["moment"]):
            problems.append(f"steps[{i}]: block.symmetry = 'quarter' takes a force along z only "
                            f"(force {step['force']}, moment {step['moment']})")
    return problems


PETSC_FAMILIES = ("ksp_", "pc_", "mat_", "mg_")  # mg_levels_* and mg_coarse_* tune multigrid levels


def petsc_option_problems(options: dict) -> list[str]:
    """Complaints about solver.petsc_options: prefix-free names of linear-solver options (ksp_*, pc_*, mg_*,
    mat_*) and scalar finite values. Whether the types they name exist in this PETSc is asked of
    PETSc where a run starts (`femcontact.solver.linear.check_petsc_options`)."""
    problems = []
    for key, value in options.items():
        name = f"solver.petsc_options.{key}"
        if not key.startswith(PETSC_FAMILIES):
            problems.append(f"{name}: not a linear-solver option (expected a name starting with "
                            f"{', '.join(PETSC_FAMILIES)}, without '-' or a prefix)")
        elif not isinstance(value, (str, int, float, bool)):
            problems.append(f"{name} = {value!r}: expected a string, number or true/false")
        elif isinstance(value, float) and not math.isfinite(value):
            problems.append(f"{name} = {value!r}: not a finite number")
    return problems


def resolve_contact(data: dict) -> dict:
    """Validate raw contact-scene data (overrides applied) and return the resolved scene: the
    contact schema of its `dim` and `geometry`, a named `accuracy` preset applied, every check."""
    head = validate({k: data[k] for k in ("dim", "geometry") if k in data},
                    {k: contact_schema(2, "peg_in_hole")[k] for k in ("dim", "geometry")})
    if isinstance(data.get("accuracy"), str):
        apply_preset(data)
    scene = validate(data, contact_schema(head["dim"], head["geometry"]))
    check_contact(scene)
    return scene


def read_toml(path) -> dict:
    path = Path(path)
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{path}: a directory, expected a TOML file") from None
    except UnicodeDecodeError as error:
        raise InputError(f"{path}: not a UTF-8 text file (byte {error.start}: {error.reason}); "
                         "TOML files are UTF-8") from None
    except OSError as error:
        raise InputError(f"{path}: cannot read ({error.strerror or error})") from None
    except tomllib.TOMLDecodeError as error:
        raise InputError(f"{path}: not valid TOML: {error}") from None


def apply_overrides(data: dict, overrides=()) -> None:
    """Set dotted keys in raw scene data: `overrides` is a {key: value} dict or a sequence of
    'key=value' texts (--set, the value read as TOML) and (key, value) pairs."""
    items = overrides.items() if isinstance(overrides, dict) else overrides
    for item in items:
        set_key(data, *(parse_assignment(item) if isinstance(item, str) else item))


def case_id(scene: dict) -> str:
    """Stable 12-hex-digit id of a resolved scene: key order and number formatting do not matter."""
    text = json.dumps(scene, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:12]
