"""J2 plasticity (femcontact.physics.plasticity, the `plasticity` effect's law) against closed forms.

Homogeneous states, exact on any mesh: a 3-D bar in uniaxial stress (P1) and a plane-strain
square in simple shear (P2, its boundary moved), loaded, unloaded, reversed and reloaded
along `PATH`, against the exact 1-D elastic-plastic curve with isotropic hardening (simple
shear is that curve for q = sqrt(3) tau, strain gamma / sqrt(3) and modulus 3 mu). The stress
agrees to round-off (relative 1e-9) and Newton converges quadratically (`assert_quadratic`;
`pytest -s` prints each increment's residual norms).
"""
import numpy as np
import pytest
from dolfinx import fem, mesh
from mpi4py import MPI

from femcontact.physics import elasticity as law
from plastic_body import PlasticBody, uniaxial_reference

E, NU = 193000.0, 0.27
HARDENING = [[0.0, 210.0], [0.002, 250.0], [1.0, 290.0]]  # a steep first piece, then the thesis' 316 slope
PATH = np.concatenate([np.linspace(0, 0.004, 5), np.linspace(0.004, -0.003, 8)[1:],
                       np.linspace(-0.003, 0.006, 7)[1:]])  # load, unload and reverse, reload past the peak


def assert_quadratic(norms, label) -> None:
    """At most 6 Newton iterations, and quadratic convergence once the residual is below 1e-2 of
    its start: e_{k+1} <= 100 e_k^2 (norms relative to the first), down to round-off (1e-12)."""
    print(f"{label:+.4f}: {len(norms) - 1} iterations, residual norms " + " ".join(f"{r:.1e}" for r in norms))
    assert len(norms) - 1 <= 6, norms
    e = np.array(norms) / norms[0]
    for now, after in zip(e, e[1:]):
        if now < 1e-2 and after > 1e-12:
            assert after <= 100 * now ** 2, norms


def fixed(V, where, component, value: fem.Constant):
    """Component `component` of u held at `value` on the boundary facets `where`."""
    facets = mesh.locate_entities_boundary(V.mesh, V.mesh.topology.dim - 1, where)
    dofs = fem.locate_dofs_topological(V.sub(component), V.mesh.topology.dim - 1, facets)
    return fem.dirichletbc(value, dofs, V.sub(component))


def test_uniaxial_stress_bar_follows_the_exact_curve_through_unloading_and_reversal():
    cube = mesh.create_unit_cube(MPI.COMM_WORLD, 1, 1, 1)
    pull = fem.Constant(cube, 0.0)

    def bcs(V):
        return [fixed(V, lambda x: np.isclose(x[k], 0.0), k, fem.Constant(cube, 0.0)) for k in range(3)] + \
            [fixed(V, lambda x: np.isclose(x[0], 1.0), 0, pull)]

    body = PlasticBody(cube, 1, E, NU, HARDENING, bcs)
    expected = uniaxial_reference(PATH, E, HARDENING)
    for strain, stress in zip(PATH, expected):
        pull.value = strain
        norms = body.increment()
        assert_quadratic(norms, strain)
        sigma = body.values(body.stress).reshape(-1, 9)
        assert np.allclose(sigma[:, 0], stress, rtol=1e-9, atol=1e-6), (strain, sigma[:, 0], stress)
        assert np.allclose(sigma[:, [1, 2, 4, 5, 8]], 0.0, atol=1e-6)  # uniaxial


def test_plane_strain_simple_shear_follows_the_exact_curve():
    square = mesh.create_unit_square(MPI.COMM_WORLD, 2, 2)
    boundary_values = []

    def bcs(V):
        boundary = mesh.locate_entities_boundary(square, 1, lambda x: np.full(x.shape[1], True))
        boundary_values.append(fem.Function(V))
        return [fem.dirichletbc(boundary_values[0], fem.locate_dofs_topological(V, 1, boundary))]

    body = PlasticBody(square, 2, E, NU, HARDENING, bcs)
    shear = boundary_values[0]
    mu = law.lame(E, NU)[1]
    expected = uniaxial_reference(PATH, 3 * mu, HARDENING) / np.sqrt(3)  # q = sqrt(3) tau, e = gamma/sqrt(3)
    for strain, tau in zip(PATH, expected):
        shear.interpolate(lambda x: np.vstack([np.sqrt(3) * strain * x[1], 0 * x[0]]))
        norms = body.increment()
        assert_quadratic(norms, strain)
        sigma = body.values(body.stress).reshape(-1, 9)
        assert np.allclose(sigma[:, 1], tau, rtol=1e-9, atol=1e-6), (strain, sigma[:, 1], tau)
        assert np.allclose(sigma[:, [0, 4, 8]], 0.0, atol=1e-6)  # no normal stress in plane-strain shear
