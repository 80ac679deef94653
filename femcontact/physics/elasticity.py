"""Elastic material laws as small functions building UFL expressions (MPa, mm).

Small strain: Hooke's law. Large strain (the `large_strain` effect): St Venant-Kirchhoff,
written with the first Piola-Kirchhoff stress so every integral stays on the
reference configuration. In 2-D, plane strain (default) or plane stress.
"""
import ufl


def lame(E, nu, plane_stress: bool = False):
    """Lame parameters (lambda, mu) in MPa; plane stress uses the reduced lambda."""
    mu = E / (2 * (1 + nu))
    lmbda = E * nu / ((1 + nu) * (1 - 2 * nu))
    if plane_stress:
        lmbda = 2 * lmbda * mu / (lmbda + 2 * mu)
    return lmbda, mu


def strain(u):
    """Small strain tensor sym(grad u)."""
    return ufl.sym(ufl.grad(u))


def hooke_stress(u, lmbda, mu):
    """Cauchy stress of linear elasticity (MPa)."""
    eps = strain(u)
    return lmbda * ufl.tr(eps) * ufl.Identity(len(u)) + 2 * mu * eps


def green_lagrange(u):
    F = ufl.Identity(len(u)) + ufl.grad(u)
    return 0.5 * (F.T * F - ufl.Identity(len(u)))


def svk_first_piola(u, lmbda, mu):
    """First Piola-Kirchhoff stress of St Venant-Kirchhoff (MPa, per reference area)."""
    E = green_lagrange(u)
    S = lmbda * ufl.tr(E) * ufl.Identity(len(u)) + 2 * mu * E
    return (ufl.Identity(len(u)) + ufl.grad(u)) * S


def energy_density(u, lmbda, mu, large_strain: bool):
    """Stored elastic energy per unit reference volume (mJ/mm^3 = MPa)."""
    eps = green_lagrange(u) if large_strain else strain(u)
    return 0.5 * lmbda * ufl.tr(eps) ** 2 + mu * ufl.inner(eps, eps)


def von_mises(stress, lmbda, mu, plane: str | None):
    """Von Mises stress (MPa) of a Cauchy-like stress; in 2-D the out-of-plane stress
    is nu*(sxx + syy) for plane strain and zero for plane stress."""
    dim = stress.ufl_shape[0]
    if dim == 2:
        szz = lmbda / (2 * (lmbda + mu)) * ufl.tr(stress) if plane == "plane_strain" else 0
        s = ufl.as_matrix([[stress[0, 0], stress[0, 1], 0], [stress[1, 0], stress[1, 1], 0], [0, 0, szz]])
    else:
        s = stress
    dev = s - ufl.tr(s) / 3 * ufl.Identity(3)
    return ufl.sqrt(1.5 * ufl.inner(dev, dev))
