"""The Hertz benchmark (docs/references.md): its scene, its measurement protocol and one run.

The simulated p0 is the largest nodal contact pressure; a comes from fitting p^2 linear
in x^2 over the outer part of the contact zone (exact for a Hertz profile). The
reference values are computed from the scene's own load, radius and material.
"""
import math
import time

import numpy as np
from mpi4py import MPI

from femcontact.references.hertz import BENCHMARK, analytic, benchmark_half_width


def scene(contact_size: float, P: float = BENCHMARK["P"], gamma: float = 10.0, increments: int = 2) -> dict:
    """The benchmark scene with a uniform contact-zone element size (mm); a falls mid-element
    when a / contact_size is a whole number plus one half."""
    from femcontact.config.scene import resolve

    b = BENCHMARK
    a = benchmark_half_width()
    return resolve({
        "name": "hertz", "dim": 2, "geometry": "block", "rigid": "indenter", "effects": ["plane_strain"],
        "block": {"width": b["width"], "height": b["height"]}, "indenter": {"shape": "cylinder", "radius": b["R"]},
        "materials": {"block": {"E": b["E"], "nu": b["nu"]}},
        "mesh": {"contact_size": contact_size, "contact_zone": max(2.5 * a, 4 * contact_size), "size_max": 8.0},
        "contact": {"gamma": gamma},
        "rigid_body": {"dofs": {"x": "held", "rz": "held"}},
        "steps": [{"name": "press", "increments": increments, "force": [0.0, -P], "load_point": "indenter"}],
    })


def reference(scene: dict) -> tuple[float, float]:
    """Analytic (a, p0) for the scene's load, cylinder radius and block material."""
    material = scene["materials"]["block"]
    P = -sum(step["force"][1] for step in scene["steps"][-1:] if step["force"])
    return analytic(P, scene["indenter"]["radius"], material["E"], material["nu"])


def measure(simulation) -> dict:
    """Simulated (a, p0) from the nodal contact pressures of a finished Hertz run."""
    nodal = simulation.recorder.nodal_values()
    comm = simulation.problem.mesh.comm
    x = np.concatenate(comm.allgather(nodal["coordinates"][:, 0][nodal["pressure"] > 0]))
    p = np.concatenate(comm.allgather(nodal["pressure"][nodal["pressure"] > 0]))
    return surface_metrics(x, p)


def surface_metrics(x, p) -> dict:
    """(a mm, p0 MPa) from nodal pressures p (MPa) at x (mm) on the loaded edge, any code's:
    p0 the largest, a from p^2 linear in x^2 over the nodes in contact (p above 1e-9 p0, which
    drops a multiplier's round-off outside contact) with x^2 >= x_max^2 / 4."""
    x, p = np.asarray(x, dtype=float), np.asarray(p, dtype=float)
    touching = p > 1e-9 * p.max()
    x, p = x[touching], p[touching]
    outer = x * x >= 0.25 * (x * x).max()
    slope, intercept = np.polyfit(x[outer] ** 2, p[outer] ** 2, 1)
    return {"a": math.sqrt(-intercept / slope), "p0": float(p.max()), "contact_nodes": int(len(p))}


def run(contact_size: float, comm=MPI.COMM_WORLD, **kwargs) -> dict:
    """Run the benchmark at one mesh size; relative errors of a and p0 and the phase timings."""
    from femcontact.solver.stepping import Simulation

    start = time.perf_counter()
    data = scene(contact_size, **kwargs)
    simulation = Simulation(data, comm)
    simulation.run()
    result = measure(simulation)
    result["wall_time"] = time.perf_counter() - start
    a, p0 = reference(data)
    result.update(error_a=result["a"] / a - 1, error_p0=result["p0"] / p0 - 1, dofs=simulation.dofs,
                  timings=simulation.timings, newton_iterations=sum(r["newton_iterations"] for r in simulation.history))
    return result
