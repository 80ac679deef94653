"""Richardson extrapolation: the mesh-converged value a convergence study measures its errors
against (`make accuracy`'s rows of every family)."""
import math


def richardson(values: list[float], ratio: float) -> tuple[float, float]:
    """Extrapolated limit and observed order from three values on meshes refined by `ratio`; the
    finest value and the order where the three do not converge (order not positive or undefined)."""
    f1, f2, f3 = values
    order = math.log(abs((f1 - f2) / (f2 - f3))) / math.log(ratio) if f2 != f3 and f1 != f2 else float("nan")
    if not math.isfinite(order) or order <= 0:
        return f3, order
    return f3 + (f3 - f2) / (ratio ** order - 1), order
