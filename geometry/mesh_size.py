"""Element-count estimate from a scene's mesh sizes, checked before gmsh runs.

gmsh meshes whatever sizes it is given: an absurd `mesh.resolution` (1e4) or a huge body
makes it run out of memory or abort. `check(scene)` estimates the number of elements from
the size field every builder uses (gmsh_tools: size h_c within the fine zones, growing by
g = GRADING / resolution per mm of distance d from them, up to h_max):

    N = integral over the meshed body of dV / (c h(d)^n),  c = sqrt(3)/4 (n = 2), 1/(6 sqrt(2)) (n = 3),

c h^n being the area or volume of an equilateral element of edge h, with the measure of
the body within d of the fine set from a tube formula (fine curves of total length L in
2-D: L d; 3-D balls of radius z around the two contact points, a top strip or disc for a
block), capped by the body's measure. It raises InputError naming the keys when N
exceeds `mesh.max_elements` (MAX_ELEMENTS by default), or when the contact size exceeds the
fine zone's half-length (a zone holding less than one element). Measured against gmsh for
the example scenes: the estimate is 0.8-2.3x the actual count (tests/test_bad_input.py checks 0.5-3x).
"""
import math

import numpy as np

from geometry import gmsh_tools
from geometry.errors import InputError

MAX_ELEMENTS = 2_000_000
"""Default ceiling on the estimated elements of one mesh (`mesh.max_elements`)."""

ELEMENT = {2: math.sqrt(3) / 4, 3: 1 / (6 * math.sqrt(2))}


def _chamfer(width: float, angle: float) -> float:
    """Length (mm) of a chamfer's face of `width` (mm) at `angle` (deg) from the axis."""
    return math.hypot(width, width / math.tan(math.radians(angle))) if width > 0 else 0.0


def size_keys(scene: dict) -> list[str]:
    """The scene keys that set the size of the meshed body."""
    if scene["geometry"] == "block":
        return ["block.width", "block.height"] + (["block.depth"] if scene["dim"] == 3 else [])
    if scene["geometry"] == "snap_fit":
        return ["spring.length", "spring.thickness", "spring.pad_height"]
    if scene["rigid"] == "hole":
        return ["peg.width", "peg.length"]
    return ["hole.block_width", "hole.depth"] + (["hole.bottom_thickness"] if scene["hole"]["kind"] == "single" else [])


def _body(scene: dict, sz):
    """(measure of the meshed body in mm^2 or mm^3, M(d): its measure within distance d of the
    fine set, the smallest distance (-zone for balls: h_c inside them))."""
    dim, z = scene["dim"], sz.zone
    if scene["geometry"] == "block":
        block = scene["block"]
        if dim == 2:
            zone = max(1, round(z / sz.h_contact)) * sz.h_contact
            return block["width"] * block["height"], lambda d: 2 * zone * d + math.pi * d * d / 2, 0.0
        part = 0.25 if block["symmetry"] == "quarter" else 1.0  # a quarter: a quarter of each
        volume = part * block["width"] * block["depth"] * block["height"]
        if scene["indenter"]["shape"] != "cylinder":  # a disc of radius z on the top face
            return volume, lambda d: part * (math.pi * z * z * d + math.pi ** 2 * z * d * d / 2
                                             + 2 * math.pi * d ** 3 / 3), 0.0
        return volume, lambda d: part * block["depth"] * (2 * z * d + math.pi * d * d / 2), 0.0  # a strip |x| <= z
    if scene["geometry"] == "snap_fit":  # a disc of radius z around each spring's apex, a quarter inside
        spring = scene["spring"]          # (3-D: swept across the width)
        depth = 1.0 if dim == 2 else spring["width"]
        measure = spring["count"] * (spring["length"] * spring["thickness"] + spring["pad_height"] ** 2 / 2) * depth
        return measure, lambda d: spring["count"] * math.pi * (z + d) ** 2 / 4 * depth, -z
    peg, hole = scene["peg"], scene["hole"]
    D, bw, depth, bt = hole["width"], hole["block_width"], hole["depth"], hole["bottom_thickness"]
    if scene["rigid"] == "peg":
        if dim == 2:
            measure = 2 * bw * depth if hole["kind"] == "two_blocks" else (D + 2 * bw) * (depth + bt) - D * depth
        else:
            measure = (D + 2 * bw) ** 2 * (depth + bt) - math.pi * D * D / 4 * depth
        fine = 8 * z + 2 * _chamfer(hole["chamfer_width"], hole["chamfer_angle"])
    else:
        measure = peg["width"] * peg["length"] if dim == 2 else math.pi * peg["width"] ** 2 / 4 * peg["length"]
        fine = 8 * z + 2 * _chamfer(peg["chamfer_width"], peg["chamfer_angle"])
    if dim == 2:  # fine stretches of total length `fine` on the boundary, six of them (their ends)
        return measure, lambda d: fine * d + 3 * math.pi * d * d, 0.0
    # balls of radius z around the two contact points, about half of each inside the body
    return measure, lambda d: 4 * math.pi / 3 * (z + d) ** 3, -z


def estimate(scene: dict, sz) -> float:
    """Estimated number of elements (triangles or tetrahedra) of the scene's mesh at sizes `sz`;
    inf when the sizes overflow double precision."""
    try:
        with np.errstate(all="ignore"):
            elements = _integrate(scene, sz)
    except OverflowError:
        return math.inf
    return elements if math.isfinite(elements) else math.inf  # NaN only from inf - inf: beyond any limit


def _integrate(scene: dict, sz) -> float:
    dim, c = scene["dim"], ELEMENT[scene["dim"]]
    measure, within, start = _body(scene, sz)
    h_c, h_max, g = sz.h_contact, sz.h_max, gmsh_tools.GRADING / sz.resolution
    extent = 10 * sum(_get(scene, key) for key in size_keys(scene))  # beyond: no part of the body left
    d_max = min((h_max - h_c) / g, extent)
    if not d_max > 0:  # one size everywhere
        return measure / (c * h_c ** dim)
    d = start + np.r_[0.0, np.geomspace(1e-3 * h_c, d_max - start, 2000)]
    covered = np.minimum(within(d), measure)
    h = np.minimum(h_max, h_c + g * np.maximum(d, 0.0))
    h_mid = 0.5 * (h[1:] + h[:-1])
    h_end = min(h_max, h_c + g * d_max)
    return float(np.sum(np.diff(covered) / (c * h_mid ** dim)) + max(measure - covered[-1], 0.0) / (c * h_end ** dim))


def check(scene: dict, sz) -> float:
    """Refuse the builder's sizes `sz` when they make the mesh too large or too coarse
    (InputError naming the keys); returns the estimated number of elements."""
    mesh = scene["mesh"]
    settings = (f"mesh.resolution = {mesh['resolution']:g}, contact size {sz.h_contact:.3g} mm, "
                f"max size {sz.h_max:.3g} mm, fine-zone half-length {sz.zone:.3g} mm")
    if sz.h_contact > sz.zone:
        raise InputError(f"mesh too coarse: the contact size exceeds the fine zone ({settings}); raise "
                            "mesh.resolution, lower mesh.contact_size or raise mesh.contact_zone")
    elements = estimate(scene, sz)
    ceiling = mesh.get("max_elements", MAX_ELEMENTS)
    if elements > ceiling:
        keys = size_keys(scene)
        sizes = ", ".join(f"{key} = {_get(scene, key):g}" for key in keys)
        raise InputError(f"mesh too large: about {elements:.2g} elements, more than mesh.max_elements = "
                            f"{ceiling:.2g} ({settings}; {sizes}); lower mesh.resolution, raise mesh.contact_size "
                            f"or mesh.size_max, shrink {' / '.join(keys)}, or raise mesh.max_elements on purpose")
    return elements


def _get(scene: dict, dotted: str):
    table, key = dotted.split(".")
    return scene[table][key]
