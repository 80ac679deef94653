"""Hertz line contact (docs/references.md): the analytic half-space solution and the benchmark's data.

Rigid cylinder of radius R pressed with P (N per mm of thickness) into a plane-strain
elastic block: E* = E / (1 - nu^2), a = sqrt(4 P R / (pi E*)), p0 = 2 P / (pi a).
"""
import math

BENCHMARK = {"P": 500.0, "R": 50.0, "E": 200000.0, "nu": 0.3, "width": 100.0, "height": 50.0}
"""The benchmark (docs/references.md): load (N/mm), cylinder radius (mm), block modulus (MPa), Poisson ratio, block size (mm)."""


def analytic(P: float, R: float, E: float, nu: float) -> tuple[float, float]:
    """(a mm, p0 MPa) of the half-space solution."""
    e_star = E / (1 - nu * nu)
    a = math.sqrt(4 * P * R / (math.pi * e_star))
    return a, 2 * P / (math.pi * a)


def benchmark_half_width() -> float:
    """a (mm) of the Hertz benchmark (docs/references.md): 0.380567 mm."""
    b = BENCHMARK
    return analytic(b["P"], b["R"], b["E"], b["nu"])[0]
