"""Compliant part mating (Whitney ch. 11): a rigid pin between cantilever contact springs.

Frame: the pin's axis is the y axis and the pin moves down (-y) to insert. Spring B (and,
with `spring.count = 2`, its mirror A at x < 0) is a cantilever of length L and thickness h
along y: x in [a, a + h], y in [0, L], root y = 0 fixed (facet `root_B`), free end up, towards
the incoming pin (the springs of a socket contact). At the free end a contact pad reaches in
by `pad_height` b: its apex (a - b, L) is a sharp 45-degree corner with a horizontal top face,
and a = w + b - interference, so the apex overlaps the pin's shank (half-width w) by the
interference: the spring's lateral deflection at full insertion. Contact facets: the pad's top
and lower face (`contact_B`). The mesh is fine (h_contact) within `zone` of the apex.

The pin (rigid) is described in its own frame: z along the axis from the nose tip (z = 0)
up, r the distance from the axis. The nose runs from the tip radius r0 at z = 0 to the
shank radius w at z = H: a flat taper, a convex or a concave circular arc (both through the
same two points as the taper of chord angle `nose_angle`; the convex arc is tangent to the
shank, the concave one to the axis at the tip), or a polyline through `nose_points`.
`nose_profile` returns the right half of the outline as straight segments and arcs.

3-D (`dim = 3`): each spring is its 2-D outline swept across its width, z in [-width/2,
width/2]; the pin is a blade, its outline swept along z without end (wider than the springs):
the same pin section in every plane z = const.
"""
import math
from dataclasses import dataclass

import numpy as np

from geometry.errors import InputError


@dataclass(frozen=True)
class Nose:
    """Right half of a pin outline in (r, z) (mm): `pieces` are ('segment', a, b) and
    ('arc', centre, radius, a, b) with a, b their end points (tip side first)."""
    kind: str
    half_width: float   # w, shank radius (mm)
    length: float       # H, axial length of the nose (mm)
    tip_radius: float   # r0 (mm)
    pin_length: float   # whole pin, tip to top (mm)
    pieces: tuple

    def radius(self, z) -> np.ndarray:
        """Pin radius r(z) (mm) at axial positions z in [0, pin_length]."""
        z = np.asarray(z, float)
        r = np.full(z.shape, self.half_width)
        for piece in self.nose_pieces:
            (_, za), (_, zb) = piece[-2], piece[-1]
            inside = (z >= za) & (z <= zb)
            r = np.where(inside, _piece_radius(piece, z), r)
        return r

    @property
    def nose_pieces(self) -> tuple:
        """The pieces between the tip flat and the shank."""
        return tuple(p for p in self.pieces if p[-1][1] > p[-2][1] and p[-2][1] < self.length)

    def depth_at(self, r: float) -> float:
        """Axial position z (mm) where the nose reaches radius r (r0 <= r <= w)."""
        if not self.tip_radius <= r <= self.half_width:
            raise InputError(f"radius {r:.6g} is outside the nose (tip radius {self.tip_radius:.6g}, "
                             f"shank {self.half_width:.6g})")
        z = np.linspace(0.0, self.length, 20001)
        return float(np.interp(r, self.radius(z), z))

    def slope_angle(self, z) -> np.ndarray:
        """Interface angle alpha(z) (rad) of the nose from the insertion axis, dr/dz = tan alpha."""
        z = np.asarray(z, float)
        step = 1e-7 * max(self.length, 1.0)
        return np.arctan((self.radius(z + step) - self.radius(z - step)) / (2 * step))



def outline(pieces, points_per_arc: int = 24) -> np.ndarray:
    """Closed polyline (x, z) (mm) of a whole pin (both halves) from its right-half pieces."""
    right = []
    for piece in pieces:
        if piece[0] == "segment":
            right += [piece[1], piece[2]]
        else:
            z = np.linspace(piece[3][1], piece[4][1], points_per_arc)
            right += list(zip(_piece_radius(piece, z), z))
    right = np.array(right, float)
    left = right[::-1] * [-1, 1]
    return np.vstack([right, left, right[:1]])


def _piece_radius(piece, z):
    if piece[0] == "segment":
        (ra, za), (rb, zb) = piece[1], piece[2]
        return ra + (np.asarray(z) - za) * (rb - ra) / (zb - za)
    _, (cr, cz), radius, (ra, za), (rb, zb) = piece
    side = 1.0 if cr < rb else -1.0  # convex: centre inside the pin
    return cr + side * np.sqrt(np.maximum(radius ** 2 - (np.asarray(z) - cz) ** 2, 0.0))


def nose_profile(peg: dict) -> Nose:
    """The pin's outline from the scene's `peg` table (snap_fit geometry)."""
    w, pin_length, kind = peg["width"] / 2, peg["length"], peg["nose"]
    if kind == "points":
        points = [tuple(map(float, p)) for p in peg["nose_points"]]
        H, r0 = points[-1][1], points[0][0]
        if abs(points[-1][0] - w) > 1e-9 * w:
            raise InputError(f"peg.nose_points: the last point's r = {points[-1][0]:.6g} must be the shank "
                             f"radius peg.width / 2 = {w:.6g}")
        nose = [("segment", a, b) for a, b in zip(points, points[1:])]
    else:
        H = peg["nose_length"]
        delta = H * math.tan(math.radians(peg["nose_angle"]))
        r0 = w - delta
        if r0 < 0:
            raise InputError(f"peg.nose_angle = {peg['nose_angle']:g}, peg.nose_length = {H:g}: the nose's radial "
                             f"rise {delta:.6g} exceeds the pin's half-width {w:.6g}")
        if kind == "taper":
            nose = [("segment", (r0, 0.0), (w, H))]
        else:
            if peg["nose_angle"] > 45.0:
                raise InputError(f"peg.nose_angle = {peg['nose_angle']:g}: an arc nose needs a chord angle <= 45 deg "
                                 "(its tangent angle runs from 0 to twice the chord angle)")
            radius = (H * H + delta * delta) / (2 * delta)
            centre = (w - radius, H) if kind == "convex" else (r0 + radius, 0.0)
            nose = [("arc", centre, radius, (r0, 0.0), (w, H))]
    if H >= pin_length:
        raise InputError(f"peg.length = {pin_length:g}: must exceed the nose length {H:.6g}")
    pieces = [("segment", (0.0, 0.0), (r0, 0.0))] if r0 > 0 else []
    pieces += nose + [("segment", (w, H), (w, pin_length)), ("segment", (w, pin_length), (0.0, pin_length))]
    return Nose(kind, w, H, r0, pin_length, tuple(pieces))


def check_points(value) -> str | None:
    """Schema check of `peg.nose_points`: [[r, z], ...] from the tip (z = 0), z increasing, r not decreasing."""
    if value == []:
        return None
    if not (isinstance(value, list) and len(value) >= 2 and all(
            isinstance(p, list) and len(p) == 2 and all(isinstance(v, (int, float)) for v in p) for p in value)):
        return "expected at least two [r, z] pairs"
    r, z = np.array(value, float).T
    if z[0] != 0 or np.any(np.diff(z) <= 0) or np.any(np.diff(r) < 0) or r[0] < 0:
        return "expected z[0] = 0, z increasing, r >= 0 and not decreasing"
    return None


@dataclass(frozen=True)
class Layout:
    """Where things are (mm): inner face x of spring B, apex (x, y), the pin's initial tip (y)."""
    inner: float
    apex: tuple
    tip_y: float
    contact_depth: float  # z on the nose where the apex first touches it


def layout(scene: dict) -> Layout:
    spring, peg = scene["spring"], scene["peg"]
    nose = nose_profile(peg)
    w, b, i, L = nose.half_width, spring["pad_height"], spring["interference"], spring["length"]
    if i >= b:
        raise InputError(f"spring.interference = {i:g}: must be below spring.pad_height = {b:g} "
                         "(the spring's face must clear the pin's shank)")
    r_apex = w - i
    if r_apex < nose.tip_radius:
        raise InputError(f"spring.interference = {i:g}: the apex (r = {r_apex:.6g}) would meet the pin's flat tip "
                         f"(radius {nose.tip_radius:.6g}); use a smaller interference or a longer nose")
    z_a = nose.depth_at(r_apex)
    return Layout(inner=w + b - i, apex=(r_apex, L), tip_y=L + peg["start_gap"] - z_a, contact_depth=z_a)


def rigid_body(scene: dict) -> dict:
    """The pin: its outline pieces, placed with its tip centre at (0, tip_y)."""
    nose, place, dim = nose_profile(scene["peg"]), layout(scene), scene["dim"]
    return {"shape": "pin", "nose": nose.kind, "half_width": nose.half_width, "length": nose.pin_length,
            "nose_length": nose.length, "pieces": nose.pieces, "corner_radius": 0.0, "chamfer_width": 0.0,
            "origin": np.array([0.0, place.tip_y, 0.0][:dim]), "rotation": np.eye(dim), "tilt": 0.0}


def points(scene: dict) -> dict:
    """Named points (mm): the pin's tip centre and top, each spring's apex (3-D: mid-width, z = 0)."""
    place, pin_length, dim = layout(scene), scene["peg"]["length"], scene["dim"]
    out = {"peg_tip": [0.0, place.tip_y], "peg_top": [0.0, place.tip_y + pin_length], "apex_B": list(place.apex)}
    if scene["spring"]["count"] == 2:
        out["apex_A"] = [-place.apex[0], place.apex[1]]
    return {name: np.array(point + [0.0] * (dim - 2)) for name, point in out.items()}


def sizes(scene: dict):
    """Defaults from the spring thickness h: contact size h/8, max size h/3 (2-D) or h/4 and h/2
    (3-D), zone = the pad height."""
    from geometry import gmsh_tools

    h = scene["spring"]["thickness"]
    contact, largest = (h / 8, h / 3) if scene["dim"] == 2 else (h / 4, h / 2)
    return gmsh_tools.sizes(scene["mesh"], contact, largest, scene["spring"]["pad_height"])


def layers(scene: dict, sz) -> int:
    """3-D: element layers across the spring's width (the 2-D mesh extruded), about 2 h_max thick."""
    return max(2, math.ceil(scene["spring"]["width"] / (2 * sz.h_max)))


def generate(scene: dict, sz) -> dict:
    """Mesh the spring(s) (current gmsh model, this rank only); returns the tag names. 3-D: the
    2-D mesh of each spring's outline at z = -width/2 is extruded across the width
    (`layers(scene, sz)` layers of prisms, each split into tetrahedra); the facets keep the
    names of the outline's edges they are swept from."""
    import gmsh

    from geometry import gmsh_tools

    spring, dim = scene["spring"], scene["dim"]
    L, h, b, width = spring["length"], spring["thickness"], spring["pad_height"], spring["width"]
    a = layout(scene).inner
    z0 = 0.0 if dim == 2 else -width / 2
    lines, surfaces, fields = {}, {}, []
    for s, label in ((1, "B"), (-1, "A"))[: spring["count"]]:
        # counter-clockwise for B; the mirror is walked the other way round
        vertices = [(a, 0.0), (a + h, 0.0), (a + h, L), (a - b, L), (a, L - b)]
        edges = [(f"root_{label}", False), (f"outer_{label}", False), (f"contact_{label}", True),
                 (f"contact_{label}", True), (f"inner_{label}", False)]
        if s < 0:
            vertices = [(-x, y) for x, y in reversed(vertices)]
            edges = [edges[(len(edges) - 2 - k) % len(edges)] for k in range(len(edges))]
        surface, tagged = gmsh_tools.polygon(vertices, edges)
        fields.append(gmsh_tools.ball_size(sz, (s * (a - b), L, z0), sz.zone))
        if dim == 2:
            surfaces[f"spring_{label}"] = [surface]
            for name, _, tag in tagged:
                lines.setdefault(name, []).append(tag)
            continue
        gmsh.model.geo.translate([(2, surface)], 0.0, 0.0, z0)
        swept = gmsh.model.geo.extrude([(2, surface)], 0.0, 0.0, width, numElements=[layers(scene, sz)])
        surfaces[f"spring_{label}"] = [swept[1][1]]  # (top, volume, one side per edge in order)
        for (name, _, _), side in zip(tagged, swept[2:]):
            lines.setdefault(name, []).append(side[1])
    gmsh.model.geo.synchronize()
    gmsh_tools.background(fields)
    gmsh.option.setNumber("Mesh.Algorithm", 6)
    cells = gmsh_tools.add_groups(dim, surfaces)
    facets = gmsh_tools.add_groups(dim - 1, {name: lines[name] for name in sorted(lines)})
    gmsh.model.mesh.generate(dim)
    return {"facets": facets, "cells": cells, "contact_facets": [n for n in facets if n.startswith("contact")],
            "supports": [n for n in facets if n.startswith("root")]}
