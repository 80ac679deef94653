"""The Coulomb return map (femcontact.physics.coulomb) against its closed form: a trial inside the
disc of radius mu p sticks (returned unchanged), one outside slips (on the rim, along the trial),
alike for numpy operands (the rigid corners) and UFL ones (the contact integrals, assembled here
over a unit square, so an integral is the value)."""
import numpy as np
import pytest
import ufl
from dolfinx import fem, mesh
from mpi4py import MPI

from femcontact.physics.coulomb import coulomb_projection, sticks

BOUND = 2.0  # mu p (N or MPa)
SCALARS = [(0.5, 0.5, True), (-1.999, -1.999, True), (2.0, 2.0, False), (3.5, 2.0, False), (-7.0, -2.0, False)]
VECTORS = [([0.3, -0.4, 1.0], [0.3, -0.4, 1.0], True),  # |t| = 1.118 < 2: stick
           ([3.0, 0.0, -4.0], [1.2, 0.0, -1.6], False)]  # |t| = 5: 2 t / 5


@pytest.fixture(scope="module")
def square():
    return mesh.create_unit_square(MPI.COMM_SELF, 1, 1)


def integral(square, expression) -> float:
    return fem.assemble_scalar(fem.form(expression * ufl.dx(domain=square)))


@pytest.mark.parametrize("trial, expected, stuck", SCALARS)
def test_2d_trial_is_clamped_to_the_bound(square, trial, expected, stuck):
    assert coulomb_projection(trial, BOUND) == pytest.approx(expected, rel=1e-15)
    assert sticks(trial, BOUND) is stuck
    t, b = fem.Constant(square, trial), fem.Constant(square, BOUND)
    assert integral(square, coulomb_projection(t, b)) == pytest.approx(expected, rel=1e-14)
    assert integral(square, ufl.conditional(sticks(t, b), 1.0, 0.0)) == float(stuck)


@pytest.mark.parametrize("trial, expected, stuck", VECTORS)
def test_3d_trial_is_scaled_onto_the_disc(square, trial, expected, stuck):
    projected = coulomb_projection(np.array(trial), BOUND)
    assert np.allclose(projected, expected, rtol=1e-14, atol=0.0)
    assert sticks(np.array(trial), BOUND) is stuck
    t, b = fem.Constant(square, np.array(trial)), fem.Constant(square, BOUND)
    symbolic = coulomb_projection(t, b)
    assert [integral(square, symbolic[k]) for k in range(3)] == pytest.approx(expected, rel=1e-14, abs=1e-300)
    if not stuck:  # on the rim of the disc
        assert np.linalg.norm(projected) == pytest.approx(BOUND, rel=1e-14)
