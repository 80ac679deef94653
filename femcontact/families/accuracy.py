"""What the families' rows in `make accuracy` share: the repository's root (their scenes) and the
Richardson extrapolation their errors are measured against."""
import math
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
"""The repository: scenes/ and studies/ are read from it."""


def richardson(values: list[float], ratio: float) -> tuple[float, float]:
    """Extrapolated limit and observed order from three values on meshes refined by `ratio`."""
    f1, f2, f3 = values
    order = math.log(abs((f1 - f2) / (f2 - f3))) / math.log(ratio) if f2 != f3 and f1 != f2 else float("nan")
    if not math.isfinite(order) or order <= 0:
        return f3, order
    return f3 + (f3 - f2) / (ratio ** order - 1), order
