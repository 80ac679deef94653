"""The remote-centre-compliance (RCC) device's geometry and its design stiffness (the thesis, ch. 5).

An inverted Gough-Whitehall-Stewart platform: base joints A, B, C, wrist joints
M, N, P, Q, R, S, six double-acting spring links of axial stiffness k (N/mm):
1 A-M, 2 B-N, 3 B-P, 4 C-Q, 5 C-R, 6 A-S. The wrist plate and the peg are one rigid
body. Device frame: origin at the peg tip O (the design compliance centre), z along
the peg from the wrist plate (z = -L) to the tip, base at z = -H. The truss models of the
device (large motions, the compliance centre under load) are the rcc family's
(femcontact.families.rcc.device); the design formula here is what a compliant support
(femcontact.effects.compliant_support) holds a peg with.
"""
import math
from dataclasses import dataclass

import numpy as np

from femcontact.errors import InputError

LINKS = (("A", "M"), ("B", "N"), ("B", "P"), ("C", "Q"), ("C", "R"), ("A", "S"))


@dataclass(frozen=True)
class Rcc:
    """Device geometry: base length b (mm), peg length L (mm), link tilt theta_L (deg),
    link stiffness k (N/mm), base-joint offset T (mm)."""
    b: float
    peg_length: float
    theta_l: float
    k: float
    offset_t: float = 0.0

    def __post_init__(self):
        for name, value in (("b", self.b), ("peg length L", self.peg_length), ("theta_L", self.theta_l),
                            ("k", self.k), ("offset T", self.offset_t)):
            if not math.isfinite(value):
                raise InputError(f"{name} = {value}: must be a finite number")
        if not 0.0 < self.theta_l < 90.0:
            raise InputError(f"theta_L = {self.theta_l} deg: must lie in (0, 90)")
        if not self.b > 0.0:
            raise InputError(f"b = {self.b} mm: must be > 0")
        if not self.k > 0.0:
            raise InputError(f"k = {self.k} N/mm: must be > 0")
        if not self.peg_length >= 0.0:
            raise InputError(f"peg length L = {self.peg_length} mm: must be >= 0")
        if not self.h > 0.0:
            raise InputError(f"peg length L = {self.peg_length} mm: must be shorter than the device height "
                             f"H = b tan(theta_L) = {self.height:.4g} mm (h = H - L = {self.h:.4g} <= 0)")
        if not 0.0 <= self.offset_t < self.h:
            raise InputError(f"offset T = {self.offset_t} mm: must lie in [0, h) with h = {self.h:.4g} mm")

    @property
    def theta(self) -> float:
        return math.radians(self.theta_l)

    @property
    def height(self) -> float:
        """H = b tan(theta_L): base plate below the tip (mm)."""
        return self.b * math.tan(self.theta)

    @property
    def h(self) -> float:
        """h = H - L: base to wrist plate (mm)."""
        return self.height - self.peg_length

    @property
    def link_length(self) -> float:
        """l_o = h / sin(theta_L) (mm), with T = 0."""
        return self.h / math.sin(self.theta)

    @property
    def raised_link_length(self) -> float:
        """Link length with the base joints raised by T: l_o - T / sin(theta_L) (mm)."""
        return self.link_length - self.offset_t / math.sin(self.theta)

    def joints(self) -> dict:
        """Joint positions (mm): A, B, C are the corners where the link lines meet."""
        b, H, L = self.b, self.height, self.peg_length
        q = self.h / math.tan(self.theta)
        r3 = math.sqrt(3.0)
        u = q * r3 / 2 - b * r3 / 3
        w = (4 * b * r3 - 3 * q * r3) / 6
        points = {"A": (-b, -b / r3, -H), "B": (b, -b / r3, -H), "C": (0, 2 * b / r3, -H),
                  "M": (-(b - q), -b / r3, -L), "N": (b - q, -b / r3, -L), "P": (b - q / 2, u, -L),
                  "Q": (q / 2, w, -L), "R": (-q / 2, w, -L), "S": (-(b - q / 2), u, -L)}
        return {name: np.array(p, dtype=float) for name, p in points.items()}

    def links(self):
        """(base ends, wrist ends), each (6, 3) in mm, links 1-6; base ends raised by T."""
        j = self.joints()
        wrist = np.array([j[w] for _, w in LINKS])
        corner = np.array([j[c] for c, _ in LINKS])
        return corner + (self.offset_t / self.h) * (wrist - corner), wrist


def formula_stiffness(device: Rcc) -> np.ndarray:
    """Reference approximation S (6x6, diagonal) at the tip: N/mm, N*mm/rad."""
    c2, s2 = math.cos(device.theta) ** 2, math.sin(device.theta) ** 2
    k, b2 = device.k, device.b ** 2
    return np.diag([3 * k * c2, 3 * k * c2, 6 * k * s2, k * b2 * s2, k * b2 * s2, 2 * k * b2 * c2])
