"""J2 (von Mises) plasticity with isotropic hardening at small strain (MPa, mm).

The radial return map is written in UFL, in closed form for a piecewise linear hardening
curve, so the stress is an expression of the displacement and of the last converged
plastic state; its derivative (`ufl.derivative`) is the consistent (algorithmic) tangent,
which keeps Newton's convergence quadratic. Tensors are 3 x 3: a 2-D strain gets zero
out-of-plane components (plane strain), or in plane stress the out-of-plane strain that makes
the returned sigma_zz vanish (`plane_stress_strain`). `QuadratureState` keeps the plastic state
at the quadrature points of the bulk integral.
"""
import basix
import numpy as np
import ufl
from dolfinx import fem

TINY = 1e-20
"""MPa^2 added under the square root of the stress norm: its derivative stays finite where
the deviatoric stress vanishes (an unstrained body); a relative change below 1e-20 at yield."""
PLANE_STRESS_STEPS = 6
"""Newton steps on the out-of-plane strain of plane stress: from the elastic guess (exact below
yield) sigma_zz falls quadratically and reaches round-off in three at 3.6 times the yield strain
in uniaxial tension; six leave a margin for the larger strain steps at a contact corner."""
ON_SURFACE = 1e-10
"""A point within this fraction above the yield stress is on the surface, not flowing: a state just
returned to the surface (round-off either side) then starts the next increment with the elastic
tangent, which is exact for unloading and only a predictor for further loading."""


def hardening_segments(points) -> list[tuple[float, float, float]]:
    """(plastic strain p_k, yield stress sigma_k, slope H_k) of each piece of the hardening
    curve through `points` [(p, sigma_y(p)), ...]; the last slope continues beyond the table,
    and a single point is perfect plasticity."""
    points = [(float(p), float(s)) for p, s in points]
    if len(points) == 1:
        return [(points[0][0], points[0][1], 0.0)]
    return [(p0, s0, (s1 - s0) / (p1 - p0)) for (p0, s0), (p1, s1) in zip(points, points[1:])]


def yield_stress(peeq, segments):
    """The yield stress (MPa) at equivalent plastic strain `peeq` (a UFL expression or float)."""
    p0, s0, h0 = segments[0]
    value = s0 + h0 * (peeq - p0)
    for p_k, s_k, h_k in segments[1:]:
        value = ufl.conditional(ufl.gt(peeq, p_k), s_k + h_k * (peeq - p_k), value)
    return value


def to_3d(tensor):
    """A 2 x 2 tensor as 3 x 3 with zero out-of-plane components; 3 x 3 unchanged."""
    if tensor.ufl_shape[0] == 3:
        return tensor
    return ufl.as_matrix([[tensor[0, 0], tensor[0, 1], 0], [tensor[1, 0], tensor[1, 1], 0], [0, 0, 0]])


def plane_stress_strain(strain, plastic_strain, peeq, lmbda, mu, segments, steps: int = PLANE_STRESS_STEPS):
    """The 3 x 3 strain of the 2 x 2 in-plane `strain` in plane stress: its out-of-plane strain
    eps_zz makes the returned sigma_zz (`return_map` from the state plastic_strain, peeq) vanish.
    Newton on eps_zz, from the elastic solution eps_zz = eps_p,zz - lambda / (lambda + 2 mu)
    tr(strain - eps_p in plane), unrolled `steps` times in UFL, so the derivative of the result
    is that of the whole local iteration (the consistent plane-stress tangent once it converged).
    `lmbda`, `mu`: the 3-D Lame parameters."""
    def full(out_of_plane):
        return ufl.as_matrix([[strain[0, 0], strain[0, 1], 0], [strain[1, 0], strain[1, 1], 0], [0, 0, out_of_plane]])

    elastic_in_plane = ufl.tr(strain) - plastic_strain[0, 0] - plastic_strain[1, 1]
    out_of_plane = plastic_strain[2, 2] - lmbda / (lmbda + 2 * mu) * elastic_in_plane
    for _ in range(steps):
        guess = ufl.variable(out_of_plane)
        sigma_zz = return_map(full(guess), plastic_strain, peeq, lmbda, mu, segments)[0][2, 2]
        out_of_plane = guess - sigma_zz / ufl.diff(sigma_zz, guess)
    return full(out_of_plane)


def return_map_strain(strain, plastic_strain, peeq, lmbda, mu, segments, plane_stress: bool = False):
    """The 3 x 3 strain `return_map` takes for the small strain `strain` (2 x 2 or 3 x 3): zero
    out-of-plane components (plane strain, `to_3d`), or with `plane_stress` the out-of-plane
    strain that makes the returned sigma_zz vanish (`plane_stress_strain`)."""
    if plane_stress:
        return plane_stress_strain(strain, plastic_strain, peeq, lmbda, mu, segments)
    return to_3d(strain)


def in_plane(tensor, dim: int):
    """The leading dim x dim block of a 3 x 3 tensor."""
    return ufl.as_matrix([[tensor[i, j] for j in range(dim)] for i in range(dim)])


def von_mises(stress):
    """Von Mises stress (MPa) of a 3 x 3 stress."""
    dev = ufl.dev(stress)
    return ufl.sqrt(1.5 * ufl.inner(dev, dev))


def return_map(strain, plastic_strain, peeq, lmbda, mu, segments):
    """The radial return from the last converged state (plastic strain, peeq) for the total
    strain `strain` (all 3 x 3): (stress, new plastic strain, new peeq).

    Trial stress sigma* = C : (strain - plastic_strain), its deviator s* and q* = sqrt(3/2 s*:s*).
    Where q* exceeds the yield stress, the plastic increment dp solves
    q* - 3 mu dp = sigma_y(peeq + dp); on the hardening piece k it is
    dp_k = (q* - sigma_k - H_k (peeq - p_k)) / (3 mu + H_k), and the piece is the last one whose
    start p_k the solution passes (q* - 3 mu (p_k - peeq) - sigma_k > 0: the left side falls
    and the right rises with dp, so these tests are true up to one piece and false after).
    Then sigma = sigma* - 3 mu dp s*/q*, plastic strain += 3/2 dp s*/q*."""
    elastic = strain - plastic_strain
    trial = lmbda * ufl.tr(elastic) * ufl.Identity(3) + 2 * mu * elastic
    deviator = ufl.dev(trial)
    q = ufl.sqrt(1.5 * ufl.inner(deviator, deviator) + TINY)
    p0, s0, h0 = segments[0]
    dp = (q - s0 - h0 * (peeq - p0)) / (3 * mu + h0)
    for p_k, s_k, h_k in segments[1:]:
        passed = ufl.gt(q - 3 * mu * (p_k - peeq) - s_k, 0)
        dp = ufl.conditional(passed, (q - s_k - h_k * (peeq - p_k)) / (3 * mu + h_k), dp)
    dp = ufl.conditional(ufl.gt(q, (1 + ON_SURFACE) * yield_stress(peeq, segments)), dp, 0.0)
    flow = 1.5 * deviator / q
    return trial - 2 * mu * dp * flow, plastic_strain + dp * flow, peeq + dp


def elastic_energy(strain, plastic_strain, lmbda, mu):
    """Stored elastic energy per unit volume (MPa) of the elastic part of a 3 x 3 strain."""
    elastic = strain - plastic_strain
    return 0.5 * lmbda * ufl.tr(elastic) ** 2 + mu * ufl.inner(elastic, elastic)


class QuadratureState:
    """The plastic state (3 x 3 plastic strain, equivalent plastic strain PEEQ) at the
    quadrature points of the rule that integrates the stiffness of Lagrange elements of
    `displacement_degree` exactly (degree 2 (k - 1), at least 1), with `dx` on those points; also
    each cell's mean (DG0: `plastic_strain_cell`, `peeq_cell`), which can be read on facets
    and at any point (exact for P1 elements, where the rule has one point per cell)."""

    def __init__(self, mesh, displacement_degree: int):
        degree = max(2 * (displacement_degree - 1), 1)
        cell = mesh.ufl_cell()
        cell_type = basix.cell.string_to_type(cell.cellname())
        self.points, weights = basix.make_quadrature(cell_type, degree)
        self.weights = weights / weights.sum()
        self.dx = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": degree, "quadrature_scheme": "default"})
        tdim = mesh.topology.dim
        cells = mesh.topology.index_map(tdim)
        self.cells = np.arange(cells.size_local + cells.num_ghosts, dtype=np.int32)

        def space(family, degree_, shape=None):
            if shape:
                element = ufl.TensorElement(family, cell, degree_, shape=shape, quad_scheme="default")
            else:
                element = ufl.FiniteElement(family, cell, degree_, quad_scheme="default")
            return fem.FunctionSpace(mesh, element)

        self.plastic_strain = fem.Function(space("Quadrature", degree, (3, 3)), name="plastic_strain")
        self.peeq = fem.Function(space("Quadrature", degree), name="PEEQ")
        self.plastic_strain_cell = fem.Function(space("DG", 0, (3, 3)), name="plastic_strain_cell")
        self.peeq_cell = fem.Function(space("DG", 0), name="PEEQ_cell")

    def functions(self) -> tuple:
        return self.plastic_strain, self.peeq, self.plastic_strain_cell, self.peeq_cell

    def expression(self, value) -> fem.Expression:
        """A UFL value compiled for evaluation at the rule's points."""
        return fem.Expression(value, self.points)

    def evaluate(self, expression: fem.Expression) -> np.ndarray:
        """Values (cells, points, components) of an expression on this rank's cells, ghosts included."""
        values = expression.eval(self.cells)
        return values.reshape(len(self.cells), len(self.points), -1)

    def assign(self, plastic_strain: np.ndarray, peeq: np.ndarray) -> None:
        """Set the state from values (cells, points, components) and refresh the cell means."""
        for function, cell_function, values in ((self.plastic_strain, self.plastic_strain_cell, plastic_strain),
                                                (self.peeq, self.peeq_cell, peeq)):
            space = function.function_space
            bs = space.dofmap.bs
            dofs = space.dofmap.list.array.reshape(len(self.cells), -1)
            function.x.array.reshape(-1, bs)[dofs] = values
            cell_dofs = cell_function.function_space.dofmap.list.array.reshape(len(self.cells))
            cell_function.x.array.reshape(-1, bs)[cell_dofs] = np.einsum("cpk,p->ck", values, self.weights)
