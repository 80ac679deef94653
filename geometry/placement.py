"""Peg placement in the hole, and the geometric checks done before any meshing.

Frames (mm). Global: 2-D x horizontal, y up; 3-D z up. The hole axis is x = 0
(3-D: x = y = 0), the hole mouth is at height 0 and the hole goes down.
Peg local frame: origin at the centre of the peg tip, 2-D (xi, eta), 3-D
(xi, zeta, eta) with eta along the peg axis towards its top; the peg occupies
|xi| <= d/2 (3-D: xi^2 + zeta^2 <= d^2/4), 0 <= eta <= length.
global = origin + rotation @ local. A positive tilt turns the peg
counter-clockwise in the x-y (3-D: x-z) plane, so its top leans towards -x.

Placement 'two_point' (the thesis, ch. 3): the peg-side point A (local (-d/2, l_d))
rests on the lowest corner of block A's mouth (x = -D/2 + gap; below a hole
chamfer when there is one) and the tip corner B (local (d/2, 0), or the top of
the peg-tip chamfer, or the tangent point of a rounded corner) touches wall B
at x = D/2 - gap. So l_d is the axial distance from the tip to the contact
point A. `gap` is measured horizontally: it is the normal gap at wall B and
gap*cos(tilt) at corner A. In 3-D this is the same construction in the x-z
plane, which is where a tilted cylinder first touches a round hole.
Placement 'centred': tip centre at depth l_d, `peg.offset` from
the hole axis along x, tilt `peg.tilt`.

Only numpy and geometry.two_point here: scene validation imports this module.
"""
import math
from dataclasses import dataclass

import numpy as np

from geometry import two_point
from geometry.errors import InputError

ARC_POINTS = 8  # points sampling each rounded peg corner in the overlap check
GENERATORS = 64  # 3-D: peg surface lines checked for overlap (multiple of 4: includes the x-z plane)
OVERLAP_TOL = 1e-9  # allowed overlap, relative to the hole width


@dataclass(frozen=True)
class Pose:
    """Placed peg: `origin` tip centre (mm), `rotation` local->global, `tilt` (rad),
    `points`: named global points (mm): peg_tip, peg_top, contact_A, contact_B."""
    origin: np.ndarray
    rotation: np.ndarray
    tilt: float
    points: dict

    def to_global(self, local) -> np.ndarray:
        """Global coordinates of local peg coordinates (rows of `local`)."""
        return self.origin + np.asarray(local, dtype=float) @ self.rotation.T


def rotation(tilt: float, dim: int) -> np.ndarray:
    """Local->global rotation of a peg tilted by `tilt` (rad), top towards -x."""
    c, s = math.cos(tilt), math.sin(tilt)
    if dim == 2:
        return np.array([[c, -s], [s, c]])
    return np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])


def local_point(xi: float, eta: float, dim: int) -> np.ndarray:
    """Point of the peg's symmetry plane (xi across, eta along the axis) in local coordinates."""
    return np.array([xi, eta]) if dim == 2 else np.array([xi, 0.0, eta])


def chamfer_height(width: float, angle: float) -> float:
    """Axial extent (mm) of a chamfer of `width` (mm) at `angle` (deg) from the axis."""
    return width / math.tan(math.radians(angle)) if width > 0 else 0.0


def _tip_corner(peg: dict) -> tuple[np.ndarray, float]:
    """Local (xi, eta) of the tip corner touching wall B, before adding the corner
    radius r along the wall normal, and r."""
    d, r = peg["width"], peg["corner_radius"]
    h_p = chamfer_height(peg["chamfer_width"], peg["chamfer_angle"])
    return np.array([d / 2 - r, h_p + r]), r


def _two_point_depth(scene: dict) -> tuple[float, float, float, float]:
    """Effective (d, D, l) for two_point.tilt_two_point, and the smallest insertion depth (mm)."""
    peg, hole = scene["peg"], scene["hole"]
    (_, eta_b), r = _tip_corner(peg)
    d_eff = peg["width"] - r
    D_eff = hole["width"] - 2 * peg["gap"] - r
    l_eff = peg["insertion_depth"] - eta_b
    return d_eff, D_eff, l_eff, eta_b + two_point.l_crit(d_eff, D_eff)


def peg_pose(scene: dict) -> Pose:
    """Pose of the peg for a validated peg_in_hole scene (see the module doc)."""
    peg, hole, dim = scene["peg"], scene["hole"], scene["dim"]
    d, length, l_d = peg["width"], peg["length"], peg["insertion_depth"]
    if peg["placement"] == "two_point":
        tilt = two_point.tilt_two_point(*_two_point_depth(scene)[:3])
        R = rotation(tilt, dim)
        h_c = chamfer_height(hole["chamfer_width"], hole["chamfer_angle"])
        corner_a = local_point(-hole["width"] / 2 + peg["gap"], -h_c, dim)
        origin = corner_a - R @ local_point(-d / 2, l_d, dim)
    else:
        tilt = math.radians(peg["tilt"])
        R = rotation(tilt, dim)
        origin = local_point(peg["offset"], -l_d, dim)
    (xi_b, eta_b), r = _tip_corner(peg)
    e_x = np.eye(dim)[0]
    points = {
        "peg_tip": origin.copy(),
        "peg_top": origin + R @ local_point(0.0, length, dim),
        "contact_A": origin + R @ local_point(-d / 2, l_d, dim),
        "contact_B": origin + R @ local_point(xi_b, eta_b, dim) + r * e_x,
    }
    return Pose(origin=origin, rotation=R, tilt=tilt, points=points)


def peg_profile(peg: dict) -> np.ndarray:
    """Half outline of the peg in local (radius, eta) (mm), from the tip centre to the
    top centre: tip face, tip chamfer or rounded corner, side, rounded top corner, top face."""
    d, length, r = peg["width"], peg["length"], peg["corner_radius"]
    cw = peg["chamfer_width"]
    if r > 0:
        a = np.linspace(-math.pi / 2, 0.0, ARC_POINTS)
        tip = np.column_stack([d / 2 - r + r * np.cos(a), r + r * np.sin(a)])
        top = np.column_stack([d / 2 - r + r * np.cos(-a[::-1]), length - r + r * np.sin(-a[::-1])])
        return np.vstack([[0.0, 0.0], tip, top, [0.0, length]])
    corner = [[d / 2 - cw, 0.0], [d / 2, chamfer_height(cw, peg["chamfer_angle"])]] if cw > 0 else [[d / 2, 0.0]]
    return np.array([[0.0, 0.0], *corner, [d / 2, length], [0.0, length]])


def _outline(scene: dict, pose: Pose) -> list[np.ndarray]:
    """Polylines on the peg's surface in global coordinates: the two sides of the 2-D
    outline, or GENERATORS surface lines of the 3-D peg."""
    profile = peg_profile(scene["peg"])
    rho, eta = profile[:, 0], profile[:, 1]
    if scene["dim"] == 2:
        return [pose.to_global(np.column_stack([s * rho, eta])) for s in (-1.0, 1.0)]
    lines = []
    for phi in np.linspace(0.0, 2 * math.pi, GENERATORS, endpoint=False):
        local = np.column_stack([rho * math.cos(phi), rho * math.sin(phi), eta])
        lines.append(pose.to_global(local))
    return lines


def _overlap(scene: dict, pose: Pose) -> np.ndarray | None:
    """First point of the peg outline inside the hole's solid (mm), or None.

    The hole's free region at height v is a radius bound b(v): D/2 along the walls,
    widening linearly through the mouth chamfer, unbounded above the mouth. On each
    outline segment the distance to the axis is convex and b is linear between the
    heights 0 and -h_c, so checking the segment ends and those crossings is exact.
    """
    hole = scene["hole"]
    D, cw, angle = hole["width"], hole["chamfer_width"], math.radians(hole["chamfer_angle"])
    h_c = chamfer_height(cw, hole["chamfer_angle"])

    def excess(p):
        v = p[-1]
        if v > 0:
            return -math.inf
        bound = D / 2 + (v + h_c) * math.tan(angle) if v > -h_c else D / 2
        return float(np.linalg.norm(p[:-1])) - bound

    for line in _outline(scene, pose):
        for p, q in zip(line[:-1], line[1:]):
            checked = [p, q]
            for level in {0.0, -h_c}:
                if (p[-1] - level) * (q[-1] - level) < 0:
                    checked.append(p + (level - p[-1]) / (q[-1] - p[-1]) * (q - p))
            for point in checked:
                if excess(point) > OVERLAP_TOL * D:
                    return point
    return None


def check_peg_in_hole(scene: dict) -> None:
    """Refuse impossible peg_in_hole inputs with an InputError naming the parameter."""
    peg, hole, dim = scene["peg"], scene["hole"], scene["dim"]
    d, D, length, l_d = peg["width"], hole["width"], peg["length"], peg["insertion_depth"]
    r, gap = peg["corner_radius"], peg["gap"]
    if D <= d:
        raise InputError(f"hole.width = {D}: must exceed peg.width = {d}")
    if dim == 3 and hole["kind"] != "single":
        raise InputError(f"hole.kind = {hole['kind']!r}: the 3-D geometry is one block with a "
                         "cylindrical hole, set hole.kind = 'single'")
    if peg["placement"] == "two_point" and D - 2 * gap <= d:
        raise InputError(f"peg.gap = {gap}: too large, hole.width - 2*gap = {D - 2 * gap:.6g} "
                         f"must exceed peg.width = {d}")
    if r > 0:
        if scene["rigid"] != "peg":
            raise InputError(f"peg.corner_radius = {r}: only a rigid peg can have rounded corners "
                             f"(rigid = {scene['rigid']!r})")
        if peg["chamfer_width"] > 0:
            raise InputError(f"peg.corner_radius = {r}: use either a corner radius or "
                             f"peg.chamfer_width = {peg['chamfer_width']}, not both")
        if r >= d / 2 or 2 * r >= length:
            raise InputError(f"peg.corner_radius = {r}: must be < peg.width/2 = {d / 2} "
                             f"and < peg.length/2 = {length / 2}")
    if scene["rigid"] == "hole" and hole["chamfer_width"] > 0:
        raise InputError(f"hole.chamfer_width = {hole['chamfer_width']}: a rigid hole has no chamfer "
                         "(set it to 0, or mesh the hole: rigid = 'peg')")
    if peg["chamfer_width"] >= d / 2:
        raise InputError(f"peg.chamfer_width = {peg['chamfer_width']}: must be < peg.width/2 = {d / 2}")
    h_p = chamfer_height(peg["chamfer_width"], peg["chamfer_angle"])
    if h_p >= length:
        raise InputError(f"peg.chamfer_width = {peg['chamfer_width']}: its axial height {h_p:.6g} "
                         f"(at chamfer_angle = {peg['chamfer_angle']}) must be < peg.length = {length}")
    if hole["chamfer_width"] >= hole["block_width"]:
        raise InputError(f"hole.chamfer_width = {hole['chamfer_width']}: must be < "
                         f"hole.block_width = {hole['block_width']}")
    h_c = chamfer_height(hole["chamfer_width"], hole["chamfer_angle"])
    if h_c >= hole["depth"]:
        raise InputError(f"hole.chamfer_width = {hole['chamfer_width']}: its depth {h_c:.6g} "
                         f"(at chamfer_angle = {hole['chamfer_angle']}) must be < hole.depth = {hole['depth']}")
    if l_d > length - r:
        raise InputError(f"peg.insertion_depth = {l_d}: exceeds peg.length = {length}"
                         + (f" less corner_radius = {r}" if r else ""))
    if peg["placement"] == "two_point":
        l_min = _two_point_depth(scene)[3]
        if l_d < l_min:
            raise InputError(f"peg.insertion_depth = {l_d}: below {l_min:.6g}, the smallest depth with "
                             f"two-point contact (l_crit = sqrt(D^2 - d^2) = {two_point.l_crit(d, D):.6g} "
                             "without chamfers/gap); use placement = 'centred' for shallower pegs")
    pose = peg_pose(scene)
    deepest = min(line[:, -1].min() for line in _outline(scene, pose))
    if deepest < -hole["depth"]:
        raise InputError(f"hole.depth = {hole['depth']}: the peg reaches {-deepest:.6g} below the mouth "
                         f"(peg.insertion_depth = {l_d}); deepen the hole")
    point = _overlap(scene, pose)
    if point is not None:
        where = ", ".join(f"{c:.6g}" for c in point)
        if peg["placement"] == "centred":
            raise InputError(f"peg.tilt = {peg['tilt']}: the centred peg (insertion_depth = {l_d}) "
                             f"overlaps the hole at ({where}); reduce the tilt or the depth")
        raise InputError(f"hole.chamfer_angle = {hole['chamfer_angle']}: the two-point peg "
                         f"(tilt {math.degrees(pose.tilt):.4g} deg) overlaps the mouth chamfer at ({where})")
