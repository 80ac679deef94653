"""A J2-plastic body on a plain DOLFINx mesh, driven through increments by a small Newton loop
that records its residual norms: the verification of femcontact.physics.plasticity on
problems with closed forms (tests/verification/test_plasticity.py)."""
import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc
from petsc4py import PETSc

from femcontact.physics import elasticity as law
from femcontact.physics import plasticity as j2


class PlasticBody:
    """Small-strain J2 body (plane strain in 2-D, or `plane_stress`) of degree `degree` with
    Dirichlet `bcs` built by `make_bcs(V)` and an optional extra residual term `extra(v)`."""

    def __init__(self, mesh, degree, E, nu, hardening, make_bcs, extra=None, plane_stress=False):
        self.mesh, self.dim = mesh, mesh.geometry.dim
        self.V = fem.VectorFunctionSpace(mesh, ("Lagrange", degree))
        self.u, v = fem.Function(self.V), ufl.TestFunction(self.V)
        self.bcs = make_bcs(self.V)
        lmbda, mu = law.lame(E, nu)
        self.state = j2.QuadratureState(mesh, degree)
        q = self.state
        segments = j2.hardening_segments(hardening)
        strain = j2.return_map_strain(law.strain(self.u), q.plastic_strain, q.peeq, lmbda, mu, segments, plane_stress)
        self.stress, plastic_strain, peeq = j2.return_map(strain, q.plastic_strain, q.peeq, lmbda, mu, segments)
        self.residual = ufl.inner(j2.in_plane(self.stress, self.dim), ufl.grad(v)) * q.dx
        if extra is not None:
            self.residual += extra(v)
        self.updates = (q.expression(plastic_strain), q.expression(peeq))
        self.plastic_area = fem.form(ufl.conditional(ufl.gt(peeq, 0), 1.0, 0.0) * q.dx)
        self.F = fem.form(self.residual)
        self.J = fem.form(ufl.derivative(self.residual, self.u, ufl.TrialFunction(self.V)))
        self.A, self.b = petsc.create_matrix(self.J), petsc.create_vector(self.F)
        self.ksp = PETSc.KSP().create(mesh.comm)
        self.ksp.setOperators(self.A)
        self.ksp.setType("preonly")
        self.ksp.getPC().setType("lu")
        self.ksp.getPC().setFactorSolverType("mumps")
        self.du = fem.Function(self.V)

    def _assemble_residual(self) -> float:
        with self.b.localForm() as local:
            local.set(0.0)
        petsc.assemble_vector(self.b, self.F)
        petsc.apply_lifting(self.b, [self.J], [self.bcs], x0=[self.u.vector], scale=-1.0)
        self.b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        petsc.set_bc(self.b, self.bcs, self.u.vector, -1.0)
        return self.b.norm()

    def increment(self, rtol=1e-11, max_iterations=25) -> list[float]:
        """Solve one increment to the Dirichlet values set, commit the plastic state; the residual
        norms of the Newton iterations (the first iteration moves the held dofs to their new
        values and the others by the tangent of the last converged state: a tangent predictor)."""
        norms = [self._assemble_residual()]
        scale = max(norms[0], 1e-30)
        while not norms[-1] <= rtol * scale and len(norms) <= max_iterations:
            self.A.zeroEntries()
            petsc.assemble_matrix(self.A, self.J, self.bcs)
            self.A.assemble()
            self.ksp.solve(self.b, self.du.vector)
            self.du.x.scatter_forward()
            self.u.x.array[:] -= self.du.x.array
            norms.append(self._assemble_residual())
        if not norms[-1] <= rtol * scale:
            raise RuntimeError(f"Newton did not converge: residual norms {norms}")
        self.state.assign(*(self.state.evaluate(e) for e in self.updates))
        return norms

    def values(self, value) -> np.ndarray:
        """A UFL value at this rank's quadrature points (cells, points, components)."""
        return self.state.evaluate(self.state.expression(value))

    def plastic_zone(self) -> float:
        return self.mesh.comm.allreduce(fem.assemble_scalar(self.plastic_area))


def uniaxial_reference(strains, E, hardening) -> np.ndarray:
    """Exact stress (MPa) of the 1-D elastic-plastic bar with isotropic hardening along a strain
    path, the plastic increment found by bisection (independent of the FE return map)."""
    p_table, s_table = np.array(hardening, float).T

    def yield_stress(p):
        if len(p_table) == 1:
            return s_table[0]
        slope = (s_table[-1] - s_table[-2]) / (p_table[-1] - p_table[-2])
        return np.interp(p, p_table, s_table) + max(p - p_table[-1], 0.0) * slope

    stresses, plastic, peeq = [], 0.0, 0.0
    for strain in strains:
        trial = E * (strain - plastic)
        if abs(trial) > yield_stress(peeq):
            low, high = 0.0, abs(trial) / E
            for _ in range(200):
                mid = 0.5 * (low + high)
                low, high = (mid, high) if abs(trial) - E * mid > yield_stress(peeq + mid) else (low, mid)
            dp = 0.5 * (low + high)
            plastic += np.sign(trial) * dp
            peeq += dp
        stresses.append(E * (strain - plastic))
    return np.array(stresses)
