"""Hertz line contact (reference §5): analytic values and the measurement protocol.

Rigid cylinder radius R pressed with P (N/mm) into a plane-strain elastic block:
a = sqrt(4 P R / (pi E*)), p0 = 2 P / (pi a), E* = E / (1 - nu^2). The simulated p0
is the largest nodal contact pressure; a comes from fitting p^2 linear in x^2 over the
outer part of the contact zone (exact for a Hertz profile).
"""
import math

import numpy as np
from mpi4py import MPI


def analytic(P: float, R: float, E: float, nu: float) -> tuple[float, float]:
    """(a mm, p0 MPa) of the half-space solution."""
    e_star = E / (1 - nu * nu)
    a = math.sqrt(4 * P * R / (math.pi * e_star))
    return a, 2 * P / (math.pi * a)


def scene(contact_size: float, P: float = 500.0, gamma: float = 10.0, increments: int = 2) -> dict:
    """The benchmark scene with a uniform contact-zone element size (mm); a falls mid-element
    when a / contact_size is a whole number plus one half."""
    from femcontact.scene import resolve

    a, _ = analytic(P, 50.0, 200000.0, 0.3)
    return resolve({
        "name": "hertz", "dim": 2, "geometry": "block", "rigid": "indenter", "effects": ["plane_strain"],
        "block": {"width": 100.0, "height": 50.0}, "indenter": {"shape": "cylinder", "radius": 50.0},
        "materials": {"block": {"E": 200000.0, "nu": 0.3}},
        "mesh": {"contact_size": contact_size, "contact_zone": max(2.5 * a, 4 * contact_size), "size_max": 8.0},
        "contact": {"gamma": gamma},
        "rigid_body": {"dofs": {"x": "held", "rz": "held"}},
        "steps": [{"name": "press", "increments": increments, "force": [0.0, -P], "load_point": "indenter"}],
    })


def measure(simulation) -> dict:
    """Simulated (a, p0) from the nodal contact pressures of a finished Hertz run."""
    nodal = simulation.recorder.nodal_values()
    comm = simulation.problem.mesh.comm
    x = np.concatenate(comm.allgather(nodal["coordinates"][:, 0][nodal["pressure"] > 0]))
    p = np.concatenate(comm.allgather(nodal["pressure"][nodal["pressure"] > 0]))
    p0 = float(p.max())
    outer = x * x >= 0.25 * (x * x).max()
    slope, intercept = np.polyfit(x[outer] ** 2, p[outer] ** 2, 1)
    return {"a": math.sqrt(-intercept / slope), "p0": p0, "contact_nodes": int(len(p))}


def run(contact_size: float, comm=MPI.COMM_WORLD, **kwargs) -> dict:
    """Run the benchmark at one mesh size; relative errors of a and p0 and the phase timings."""
    import time

    from femcontact.simulation import Simulation

    start = time.perf_counter()
    simulation = Simulation(scene(contact_size, **kwargs), comm)
    simulation.run()
    result = measure(simulation)
    result["wall_time"] = time.perf_counter() - start
    a, p0 = analytic(kwargs.get("P", 500.0), 50.0, 200000.0, 0.3)
    result.update(error_a=result["a"] / a - 1, error_p0=result["p0"] / p0 - 1, dofs=simulation.dofs,
                  timings=simulation.timings, newton_iterations=sum(r["newton_iterations"] for r in simulation.history))
    return result
