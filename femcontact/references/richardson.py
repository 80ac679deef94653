"""Richardson extrapolation: the mesh-converged value a convergence study measures its errors
against (`make accuracy`'s rows of every family)."""
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
