"""J2 (von Mises) plasticity of the deformable body with isotropic hardening (small strain; 3-D,
plane strain or, with `plane_stress`, plane stress: sigma_zz = 0 at every quadrature point).

The initial yield stress is the body's `materials.<body>.yield_stress`; hardening is linear
(`plasticity.hardening_modulus`, MPa) or piecewise linear through `plasticity.hardening`
[[plastic strain, yield stress], ...]. The radial return map (physics/plasticity.py) runs at
the bulk integral's quadrature points, from the plastic state of the last converged increment
that this effect owns (`state`/`restore`/`commit`), so a cut increment or a dynamic step
starts from the right history. The bulk term it adds, -2 mu eps_p : grad v, turns the
elastic stress into the returned one; its derivative is the consistent tangent, and since
that depends on the state the solver assembles the bulk stiffness at every iteration.
Contact (Nitsche's stress), von Mises and energy outputs use the returned stress from each
cell's mean plastic state (exact for P1 elements). Adds history columns `max_peeq` and
`plastic_zone` (area in 2-D, mm^2 per unit thickness; volume in 3-D, mm^3, where PEEQ > 0)
and the cell field `peeq` (fields.npz, ParaView).
"""
import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI

from femcontact.effects.base import Effect
from femcontact.physics import elasticity as law
from femcontact.physics import plasticity as j2


class Plasticity(Effect):
    name = "plasticity"

    def build(self, problem) -> None:
        scene, dim, u = problem.scene, problem.dim, problem.u
        lmbda, mu = law.lame(problem.constants["E"], problem.constants["nu"])  # 3-D: plane stress solves eps_zz
        segments = j2.hardening_segments(hardening_points(scene, problem.deformable))
        self.quadrature = j2.QuadratureState(problem.mesh, scene["mesh"]["degree"])
        q = self.quadrature
        plane_stress = "plane_stress" in problem.effects

        def strain(plastic_strain, peeq):
            return j2.return_map_strain(law.strain(u), plastic_strain, peeq, lmbda, mu, segments, plane_stress)

        points_strain = strain(q.plastic_strain, q.peeq)
        stress, plastic_strain, peeq = j2.return_map(points_strain, q.plastic_strain, q.peeq, lmbda, mu, segments)
        if plane_stress:  # the elastic plane-stress term (problem.stress) turned into the returned stress
            change = j2.in_plane(stress, dim) - problem.stress
        else:  # sigma = C : (eps - eps_p), and eps_p has no trace
            change = -2 * mu * j2.in_plane(plastic_strain, dim)
        problem.add_bulk(ufl.inner(change, ufl.grad(problem.v)), q.dx)
        self.updates = (q.expression(plastic_strain), q.expression(peeq))
        self.plastic_zone = fem.form(ufl.conditional(ufl.gt(peeq, 0), 1.0, 0.0) * q.dx)
        cell_strain = strain(q.plastic_strain_cell, q.peeq_cell)
        stress, cell_plastic_strain, _ = j2.return_map(cell_strain, q.plastic_strain_cell, q.peeq_cell, lmbda, mu,
                                                       segments)
        problem.stress = j2.in_plane(stress, dim)
        problem.von_mises = j2.von_mises(stress)
        problem.energy_density = j2.elastic_energy(cell_strain, cell_plastic_strain, lmbda, mu)

    def _updated(self) -> tuple[np.ndarray, np.ndarray]:
        """The state the current displacement returns to, from the last converged one."""
        return tuple(self.quadrature.evaluate(expression) for expression in self.updates)

    def commit(self, dt: float) -> None:
        self.quadrature.assign(*self._updated())

    def state(self) -> dict:
        return {f.name: f.x.array.copy() for f in self.quadrature.functions()}

    def restore(self, state: dict) -> None:
        for function in self.quadrature.functions():
            function.x.array[:] = state[function.name]

    def outputs(self) -> dict:
        comm = self.problem.mesh.comm
        n_owned = self.problem.mesh.topology.index_map(self.problem.dim).size_local
        peeq = self._updated()[1][:n_owned]
        return {"max_peeq": comm.allreduce(float(peeq.max(initial=0.0)), op=MPI.MAX),
                "plastic_zone": comm.allreduce(fem.assemble_scalar(self.plastic_zone), op=MPI.SUM)}

    def cell_fields(self) -> dict:
        return {"peeq": self.quadrature.peeq_cell}


def hardening_points(scene: dict, body: str) -> list:
    """The hardening curve [(plastic strain, yield stress (MPa)), ...] of the deformable body."""
    settings = scene["plasticity"]
    if settings["hardening"]:
        return settings["hardening"]  # its first row is the body's yield stress (config/scene.py)
    yield_stress = scene["materials"][body]["yield_stress"]
    return [(0.0, yield_stress), (1.0, yield_stress + settings["hardening_modulus"])]
