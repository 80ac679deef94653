"""Frictionless normal contact with the rigid body (always built).

Nitsche's method (default): pressure p = [p_sigma - gamma_N g]_+ with gamma_N = gamma E / h,
or penalty p = [-gamma_N g]_+, against the rigid body's analytic signed distance g in
its own frame. Provides `problem.contact` (xi, gap, normal, normal_local, pressure) for
friction and outputs, and the normal traction p n.
"""
from types import SimpleNamespace

import ufl

from femcontact.effects.base import Effect
from femcontact.physics.signed_distance import signed_distance


class NormalContact(Effect):
    name = "contact"

    def constants(self, scene: dict, body: str) -> dict:
        contact = scene["contact"]
        return {"gamma": contact["gamma"], "theta": contact["theta"]}

    def build(self, problem) -> None:
        c, rigid, scene = problem.constants, problem.rigid, problem.scene
        x = ufl.SpatialCoordinate(problem.mesh) + problem.u
        xi = ufl.variable(rigid.to_local(x, rigid.variable))
        gap = signed_distance(problem.shape, xi)
        normal_local = ufl.diff(gap, xi)
        normal = rigid.to_global_direction(normal_local, rigid.variable)
        p_sigma = ufl.dot(problem.stress * ufl.FacetNormal(problem.mesh), normal)
        gamma_n = c["gamma"] * c["E"] / ufl.CellDiameter(problem.mesh)
        trial = p_sigma - gamma_n * gap if scene["contact"]["method"] == "nitsche" else -gamma_n * gap
        # [trial]_+ with the kink counted as active, so a body touching with zero force
        # already gets the contact stiffness in Newton's first iteration
        pressure = ufl.conditional(ufl.ge(trial, 0), trial, 0.0)
        problem.contact = SimpleNamespace(xi=xi, gap=gap, normal=normal, normal_local=normal_local,
                                          pressure=pressure)
        problem.add_traction(pressure * normal)
        if scene["contact"]["theta"] != 0:
            # Nitsche's theta-term: -(theta/gamma_N) (p_sigma(u) - p) p_sigma(v)
            dstress = ufl.derivative(problem.stress, problem.u, problem.v)
            p_sigma_v = ufl.dot(dstress * ufl.FacetNormal(problem.mesh), normal)
            problem.add_contact_term(-c["theta"] / gamma_n * (p_sigma - pressure) * p_sigma_v)

    def contact_stiffness(self) -> float:
        """gamma_N = gamma E / h_contact (N/mm^3), the penalty part of the pressure per mm of gap."""
        c = self.problem.constants
        return float(c["gamma"].value * c["E"].value) / self.problem.contact_size
