"""Richardson extrapolation: the mesh-converged value a convergence study measures its errors
against (`make accuracy`'s rows of every family), and the discretisation error of the finest mesh
where the meshes converge monotonically (`finest_error`) or do not (`range_error`)."""
import math


def richardson(values: list[float], ratio: float) -> tuple[float, float]:
    """Extrapolated limit and observed order from three values on meshes refined by `ratio`; the
    finest value and the order where the three do not converge monotonically (their two steps of
    opposite sign or nil: order undefined, nan) or the order is not positive."""
    f1, f2, f3 = values
    monotone = (f1 - f2) * (f2 - f3) > 0
    order = math.log((f1 - f2) / (f2 - f3)) / math.log(ratio) if monotone else float("nan")
    if not math.isfinite(order) or order <= 0:
        return f3, order
    return f3 + (f3 - f2) / (ratio ** order - 1), order


SAFETY_FACTOR = 3.0
"""Roache's factor of safety where the observed order is not the discretisation's (Roache,
J. Fluids Eng. 133 (2011) 115501: "one at least reverts to using p_th and FS = 3")."""


def finest_error(values: list[float], ratio: float, formal_order: float) -> tuple[float | None, float]:
    """The estimated relative error of the finest of three or more values on meshes each refined
    by `ratio`, and the order it was estimated with. Only where every step moves the same way and
    each is smaller than the one before (a coarser rung that moves the other way, or by less,
    shows the three finest are not yet converging): Richardson's |finest - limit| / |limit| from
    the three finest at their observed order up to `formal_order`; at an observed order above
    it, the formal order with a factor of safety 3 (3 |f3 - f2| / (ratio^p - 1) / |f3|). Else
    None (and nan)."""
    steps = [b - a for a, b in zip(values[:-1], values[1:])]
    shrinking = all(s * steps[0] > 0 for s in steps) and all(abs(b) < abs(a) for a, b in zip(steps[:-1], steps[1:]))
    limit, order = richardson(values[-3:], ratio)
    f2, f3 = values[-2], values[-1]
    if not shrinking or not (math.isfinite(order) and order > 0) or not f3:
        return None, float("nan")
    if order <= formal_order:
        return (abs(f3 - limit) / abs(limit) if limit else None), order
    return SAFETY_FACTOR * abs(f3 - f2) / (ratio ** formal_order - 1) / abs(f3), formal_order


RANGE_FACTOR = 3.0
"""The factor on the data range where the meshes do not converge monotonically: Eca and
Hoekstra's uncertainty for oscillatory convergence and anomalous behaviour, U = 3 Delta_M
(J. Mar. Sci. Technol., doi:10.1007/s00773-008-0018-1, appendix 1)."""


def spread(values: list[float]) -> float | None:
    """(largest - smallest) / |finest| of `values` (coarsest first); None where the finest is 0."""
    return (max(values) - min(values)) / abs(values[-1]) if values[-1] else None


def range_error(values: list[float]) -> float | None:
    """The relative uncertainty of the finest of `values` (coarsest first) where they do not
    converge monotonically: 3 `spread(values)`. Eca and Hoekstra take the range over every mesh
    of a study; pass the meshes an estimate stands on (the three finest). None where the finest
    is 0."""
    relative = spread(values)
    return None if relative is None else RANGE_FACTOR * relative
