"""Coulomb friction's return map, one law for the contact integrals (UFL) and the rigid corners (numpy).

The trial tangential traction or force (the elastic predictor: what the contact carries if it
sticks) is projected on the disc of radius `bound` = mu p (mu the friction coefficient, p >= 0
the normal pressure or force): inside the disc the contact sticks and keeps the trial, outside
it slips and the traction lies on the disc's rim, along the trial. In 2-D the trial is a
scalar (its component along the tangent), in 3-D a vector. Each function takes UFL
expressions (and returns one) or numbers and numpy arrays.
"""
import numpy as np
import ufl

SIZE_FLOOR = 1e-30
"""Added to |trial|^2 under the square root (3-D), so the map and its derivative stay finite at a zero trial."""


def _symbolic(*operands) -> bool:
    return any(isinstance(x, ufl.core.expr.Expr) for x in operands)


def trial_size(trial):
    """|trial| (MPa or N)."""
    if _symbolic(trial):
        return abs(trial) if ufl.shape(trial) == () else ufl.sqrt(ufl.dot(trial, trial) + SIZE_FLOOR)
    return abs(trial) if np.ndim(trial) == 0 else np.sqrt(trial @ trial + SIZE_FLOOR)


def sticks(trial, bound):
    """Whether the contact sticks: |trial| < bound (a UFL condition or a bool)."""
    size = trial_size(trial)
    return ufl.lt(size, bound) if _symbolic(size, bound) else bool(size < bound)


def coulomb_projection(trial, bound):
    """The tangential traction (MPa) or force (N) Coulomb friction allows for `trial`, given the
    slip bound mu p (same units): in 2-D `trial` clamped to [-bound, bound], in 3-D scaled onto
    the disc where it lies outside."""
    symbolic = _symbolic(trial, bound)
    if (ufl.shape(ufl.as_ufl(trial)) if symbolic else np.shape(trial)) == ():
        low, high = (ufl.max_value, ufl.min_value) if symbolic else (np.maximum, np.minimum)
        return low(high(trial, bound), -bound)
    size = trial_size(trial)
    if symbolic:
        return ufl.conditional(ufl.le(size, bound), trial, bound * trial / size)
    return trial if size <= bound else bound * trial / size
