"""Hertz contact: the analytic half-space solutions and the benchmarks' data.

Line contact (docs/references.md): a rigid cylinder of radius R pressed with P (N per mm of
thickness) into a plane-strain elastic block: E* = E / (1 - nu^2), a = sqrt(4 P R / (pi E*)),
p0 = 2 P / (pi a). Point contact: a rigid sphere of radius R pressed with P (N) into an
elastic half-space: a = (3 P R / (4 E*))^(1/3), p0 = 3 P / (2 pi a^2), p(r) = p0 sqrt(1 - r^2/a^2).
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


BENCHMARK_3D = {"P": 2000.0, "R": 50.0, "E": 200000.0, "nu": 0.3, "width": 100.0, "depth": 100.0, "height": 50.0}
"""Sphere on a block: load (N, on the whole sphere), sphere radius (mm), block modulus (MPa), Poisson
ratio, block size (mm; modelled as its quarter x, y >= 0)."""


def analytic_sphere(P: float, R: float, E: float, nu: float) -> tuple[float, float]:
    """(a mm, p0 MPa) of a rigid sphere on an elastic half-space."""
    e_star = E / (1 - nu * nu)
    a = (3 * P * R / (4 * e_star)) ** (1 / 3)
    return a, 3 * P / (2 * math.pi * a * a)


def benchmark_radius_3d() -> float:
    """a (mm) of the sphere benchmark: 0.698807 mm (p0 1955.49 MPa)."""
    b = BENCHMARK_3D
    return analytic_sphere(b["P"], b["R"], b["E"], b["nu"])[0]
