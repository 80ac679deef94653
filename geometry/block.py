"""Test-bench block under a rigid indenter (scene geometry = 'block').

2-D: x in [-w/2, w/2], y in [-h, 0]; 3-D: x in [-w/2, w/2], y in [-depth/2, depth/2],
z in [-h, 0] (front: y = -depth/2, back: y = +depth/2). The indenter touches the top
at the origin. Fine zone: 2-D, the top edge between x = -z and z = +z has exactly
uniform node spacing h_contact with a node at x = 0 (transfinite curve; the zone
half-length z is rounded to a whole number k of elements, z = k*h_contact); 3-D, the top
strip |x| <= z (cylinder indenter) or the top disc of radius z (sphere, flat punch). Away
from the zone the size grows linearly (gmsh_tools.GRADING) up to the maximum size.
3-D with block.symmetry = 'quarter': only x >= 0, y >= 0 is meshed, its faces x = 0 and
y = 0 named symmetry_x and symmetry_y (their normal displacement held).
"""
import math

from geometry.errors import InputError
from geometry import gmsh_tools


def sizes(scene: dict) -> gmsh_tools.Sizes:
    """Defaults from s = min(width, height): contact size s/100, max size s/5; zone s/10,
    and for a flat indenter at least 0.6 times its width (covering its edges)."""
    block, indenter = scene["block"], scene["indenter"]
    scale = min(block["width"], block["height"])
    zone = max(scale / 10, 0.6 * indenter["width"]) if indenter["shape"] == "flat" else scale / 10
    return gmsh_tools.sizes(scene["mesh"], scale / 100, scale / 5, zone)


def zone_elements(sz: gmsh_tools.Sizes) -> int:
    """Number k of elements on each half of the 2-D fine top zone (zone = k*h_contact)."""
    return max(1, round(sz.zone / sz.h_contact))


def _generate_2d(scene: dict, sz: gmsh_tools.Sizes) -> dict:
    import gmsh

    w, h = scene["block"]["width"], scene["block"]["height"]
    k = zone_elements(sz)
    z = k * sz.h_contact
    if z >= w / 2:
        raise InputError(f"mesh.contact_zone: the fine zone |x| <= {z:.6g} must be narrower than the block")
    vertices = [(-w / 2, -h), (w / 2, -h), (w / 2, 0.0), (z, 0.0), (0.0, 0.0), (-z, 0.0), (-w / 2, 0.0)]
    edges = [("bottom", False), ("right", False), ("top", False), ("top", True), ("top", True),
             ("top", False), ("left", False)]
    surface, lines = gmsh_tools.polygon(vertices, edges)
    fine = [tag for _, is_fine, tag in lines if is_fine]
    for tag in fine:  # x = 0 is a geometry vertex, so the node there is exact
        gmsh.model.geo.mesh.setTransfiniteCurve(tag, k + 1)
    gmsh.model.geo.synchronize()
    gmsh_tools.background([gmsh_tools.distance_threshold(sz, curves=fine, curve_length=z)])
    gmsh.option.setNumber("Mesh.Algorithm", 6)
    by_name = {}
    for name, _, tag in lines:
        by_name.setdefault(name, []).append(tag)
    cells = gmsh_tools.add_groups(2, {"block": [surface]})
    facets = gmsh_tools.add_groups(1, by_name)
    gmsh.model.mesh.generate(2)
    return {"facets": facets, "cells": cells}


def _generate_3d(scene: dict, sz: gmsh_tools.Sizes) -> dict:
    import gmsh

    block = scene["block"]
    w, h, depth = block["width"], block["height"], block["depth"]
    if sz.zone >= w / 2:
        raise InputError(f"mesh.contact_zone = {sz.zone:.6g}: the fine zone must be narrower than the block")
    quarter = bool(symmetry_planes(scene))
    x0, y0 = (0.0, 0.0) if quarter else (-w / 2, -depth / 2)
    volume = gmsh.model.occ.addBox(x0, y0, -h, w / 2 - x0, depth / 2 - y0, h)
    gmsh.model.occ.synchronize()
    sides = {(0, x0): "symmetry_x" if quarter else "left", (0, w / 2): "right",
             (1, y0): "symmetry_y" if quarter else "front", (1, depth / 2): "back", (2, -h): "bottom", (2, 0.0): "top"}
    faces = {}
    for _, tag in gmsh.model.getBoundary([(3, volume)], oriented=False):
        c = gmsh.model.occ.getCenterOfMass(2, tag)
        faces[next(v for (axis, value), v in sides.items() if math.isclose(c[axis], value, abs_tol=1e-9 * w))] = [tag]
    lateral = "Abs(x)" if scene["indenter"]["shape"] == "cylinder" else "Sqrt(x^2+y^2)"
    gmsh_tools.background([gmsh_tools.graded(sz, f"Sqrt(Max(0, {lateral}-{sz.zone!r})^2+z^2)")])
    cells = gmsh_tools.add_groups(3, {"block": [volume]})
    order = ("top", "bottom", sides[0, x0], "right", sides[1, y0], "back")
    facets = gmsh_tools.add_groups(2, {n: faces[n] for n in order})
    gmsh.option.setNumber("Mesh.OptimizeThreshold", 0.45)  # optimise tetrahedra of quality below this
    gmsh.model.mesh.generate(3)
    return {"facets": facets, "cells": cells}


def generate(scene: dict, sz: gmsh_tools.Sizes) -> dict:
    """Build and mesh the block (current gmsh model, this rank only); returns the tag names."""
    names = _generate_2d(scene, sz) if scene["dim"] == 2 else _generate_3d(scene, sz)
    return {**names, "contact_facets": ["top"], "supports": ["bottom"], "symmetry": symmetry_planes(scene)}


def symmetry_planes(scene: dict) -> dict[str, int]:
    """Facet tag name -> the displacement component its symmetry plane holds (0: x, 1: y)."""
    return {"symmetry_x": 0, "symmetry_y": 1} if scene["block"].get("symmetry") == "quarter" else {}
