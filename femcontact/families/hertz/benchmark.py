"""The Hertz benchmarks: their scenes, their measurement protocol and one run.

2-D (docs/references.md): a rigid cylinder on a plane-strain block. 3-D: a rigid sphere on a
block, its quarter x, y >= 0 meshed with symmetry planes, the contact zone r <= 1.5 a
meshed at the uniform size h_c and graded outside. The simulated p0 is the largest nodal
contact pressure; a comes from fitting p^2 linear in r^2 over the outer part of the
contact zone (exact for a Hertz profile, line or point). The reference values are
computed from the scene's own load, radius and material.
"""
import math
import time

import numpy as np

from femcontact.references.hertz import (BENCHMARK, BENCHMARK_3D, analytic, analytic_sphere, benchmark_half_width,
                                         benchmark_radius_3d)

QUARTER = 4
"""The 3-D scene models a quarter of the block: its force is P / 4."""


def scene(contact_size: float, P: float = BENCHMARK["P"], gamma: float = 10.0, increments: int = 2,
          degree: int = 1) -> dict:
    """The benchmark scene with a uniform contact-zone element size (mm) and Lagrange elements
    of `degree`; a falls mid-element when a / contact_size is a whole number plus one half."""
    from femcontact.config.scene import resolve_contact

    b = BENCHMARK
    a = benchmark_half_width()
    return resolve_contact({
        "name": "hertz", "dim": 2, "geometry": "block", "rigid": "indenter", "effects": ["plane_strain"],
        "block": {"width": b["width"], "height": b["height"]}, "indenter": {"shape": "cylinder", "radius": b["R"]},
        "materials": {"block": {"E": b["E"], "nu": b["nu"]}},
        "mesh": {"contact_size": contact_size, "contact_zone": max(2.5 * a, 4 * contact_size), "size_max": 8.0,
                 "degree": degree},
        "contact": {"gamma": gamma},
        "rigid_body": {"dofs": {"x": "held", "rz": "held"}},
        "steps": [{"name": "press", "increments": increments, "force": [0.0, -P], "load_point": "indenter"}],
    })


def scene_3d(contact_size: float, P: float = BENCHMARK_3D["P"], gamma: float = 10.0, increments: int = 2,
             degree: int = 1) -> dict:
    """The sphere benchmark's quarter model with a uniform element size `contact_size` (mm) on
    r <= 1.5 a and Lagrange elements of `degree`; a falls mid-element when a / contact_size is
    a whole number plus one half."""
    from femcontact.config.scene import resolve_contact

    b = BENCHMARK_3D
    a = benchmark_radius_3d()
    return resolve_contact({
        "name": "hertz_3d", "dim": 3, "geometry": "block", "rigid": "indenter",
        "block": {"width": b["width"], "depth": b["depth"], "height": b["height"], "symmetry": "quarter"},
        "indenter": {"shape": "sphere", "radius": b["R"]},
        "materials": {"block": {"E": b["E"], "nu": b["nu"]}},
        "mesh": {"contact_size": contact_size, "contact_zone": 1.5 * a, "size_max": 8.0, "degree": degree},
        "contact": {"gamma": gamma},
        "rigid_body": {"dofs": {name: "held" for name in ("x", "y", "rx", "ry", "rz")}},
        "steps": [{"name": "press", "increments": increments, "force": [0.0, 0.0, -P / QUARTER],
                   "load_point": "indenter"}],
    })


def reference(scene: dict) -> tuple[float, float]:
    """Analytic (a, p0) for the scene's load, indenter radius and block material."""
    material = scene["materials"]["block"]
    P = -sum(step["force"][-1] for step in scene["steps"][-1:] if step["force"])
    if scene["dim"] == 2:
        return analytic(P, scene["indenter"]["radius"], material["E"], material["nu"])
    P *= QUARTER if scene["block"]["symmetry"] == "quarter" else 1
    return analytic_sphere(P, scene["indenter"]["radius"], material["E"], material["nu"])


def surface_nodes(simulation) -> tuple[np.ndarray, np.ndarray]:
    """(r mm, p MPa) of every node of the loaded surface, gathered on all ranks, sorted by r:
    r = x in 2-D, sqrt(x^2 + y^2) in 3-D; p the nodal contact pressure (0 outside). Linear
    elements: the pressure lumped to the vertices (`Recorder.nodal_values`); quadratic ones:
    the pressure at every node of the displacement, vertices and edge midpoints, recovered from
    the cells (`Recorder.recovered_pressure`), where lumping would smear the zone's edge."""
    recorder = simulation.recorder
    comm, dim = simulation.problem.mesh.comm, simulation.problem.dim
    if simulation.problem.scene["mesh"]["degree"] == 1:
        nodal = recorder.nodal_values()
        on = nodal["on_surface"]
        x, pressure = nodal["coordinates"][on], np.maximum(nodal["pressure"][on], 0.0)
    else:
        x, pressure = recorder.recovered_pressure()
    r = np.concatenate(comm.allgather(x[:, 0] if dim == 2 else np.hypot(x[:, 0], x[:, 1])))
    p = np.concatenate(comm.allgather(pressure))
    order = np.argsort(r, kind="stable")
    return r[order], p[order]


def measure(simulation) -> dict:
    """Simulated (a, p0) from the nodal contact pressures of a finished Hertz run."""
    return surface_metrics(*surface_nodes(simulation))


def surface_metrics(x, p) -> dict:
    """(a mm, p0 MPa) from nodal pressures p (MPa) at distances x (mm) from the first contact
    point on the loaded surface, any code's: p0 the largest, a from p^2 linear in x^2 over the
    nodes in contact (p above 1e-9 p0, which drops a multiplier's round-off outside contact)
    with x^2 >= x_max^2 / 4."""
    x, p = np.asarray(x, dtype=float), np.asarray(p, dtype=float)
    touching = p > 1e-9 * p.max()
    x, p = x[touching], p[touching]
    outer = x * x >= 0.25 * (x * x).max()
    slope, intercept = np.polyfit(x[outer] ** 2, p[outer] ** 2, 1)
    return {"a": math.sqrt(-intercept / slope), "p0": float(p.max()), "contact_nodes": int(len(p))}


def run(contact_size: float, comm=None, dim: int = 2, **kwargs) -> dict:
    """Run the benchmark (2-D or 3-D) at one mesh size on `comm` (default: every rank); relative
    errors of a and p0 and the phase timings."""
    from mpi4py import MPI

    from femcontact.solver.stepping import Simulation

    start = time.perf_counter()
    data = (scene if dim == 2 else scene_3d)(contact_size, **kwargs)
    simulation = Simulation(data, comm or MPI.COMM_WORLD)
    simulation.run()
    result = measure(simulation)
    result["wall_time"] = time.perf_counter() - start
    a, p0 = reference(data)
    result.update(error_a=result["a"] / a - 1, error_p0=result["p0"] / p0 - 1, dofs=simulation.dofs,
                  timings=simulation.timings, newton_iterations=sum(r["newton_iterations"] for r in simulation.history))
    return result
