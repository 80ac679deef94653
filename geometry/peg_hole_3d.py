"""3-D peg in a cylindrical hole (OCC kernel; frames and placement: geometry/placement.py).

Hole block (peg rigid): box [-(D/2 + bw), D/2 + bw]^2 x [-(depth + bottom_thickness), 0]
minus the cylinder of diameter D down to -depth, with an optional conical mouth chamfer.
Meshed peg (hole rigid): cylinder of diameter d and the given length with an optional
conical tip chamfer, placed by placement.peg_pose. Fine zones (size h_contact) are balls
of radius `zone` around the two expected contact points contact_A (the mouth edge at
x = -D/2) and contact_B (the wall at x = +D/2 at the tip's depth); the size grows
linearly with the distance (gmsh_tools.GRADING) up to the maximum size.
"""
import math

import numpy as np

from geometry import gmsh_tools
from geometry.placement import chamfer_height, peg_pose

ABOVE = 1.0  # how far (mm) cutting tools reach above the mouth, for clean booleans


def sizes(scene: dict) -> gmsh_tools.Sizes:
    """Default sizes from a length scale s: contact size s/40, max size s/4, zone s/10, with
    s = min(block_width, depth) for the block, min(width, length) for a meshed peg."""
    scale = gmsh_tools.meshed_scale(scene)
    return gmsh_tools.sizes(scene["mesh"], scale / 40, scale / 4, scale / 10)


def _hole_block(scene: dict) -> tuple[int, dict]:
    """The hole block volume and its faces by tag name."""
    import gmsh

    hole, occ = scene["hole"], gmsh.model.occ
    D, bw, depth, bt = hole["width"], hole["block_width"], hole["depth"], hole["bottom_thickness"]
    cw, angle = hole["chamfer_width"], math.radians(hole["chamfer_angle"])
    h_c = chamfer_height(cw, hole["chamfer_angle"])
    half = D / 2 + bw
    box = occ.addBox(-half, -half, -depth - bt, 2 * half, 2 * half, depth + bt)
    tools = [(3, occ.addCylinder(0, 0, -depth, 0, 0, depth + ABOVE, D / 2))]
    if cw > 0:
        tools.append((3, occ.addCone(0, 0, -h_c, 0, 0, h_c + ABOVE, D / 2, D / 2 + (h_c + ABOVE) * math.tan(angle))))
    (volume,), _ = occ.cut([(3, box)], tools)
    occ.synchronize()
    support = hole["support"] == "outer"
    faces = {"hole_wall": [], "hole_mouth": [], "hole_chamfer": [], "hole_bottom": [], "support": []}
    for _, tag in gmsh.model.getBoundary([volume], oriented=False):
        kind = gmsh.model.getType(2, tag)
        x, y, z = occ.getCenterOfMass(2, tag)
        tol = 1e-9 * half
        if kind == "Cylinder":
            faces["hole_wall"].append(tag)
        elif kind == "Cone":
            faces["hole_chamfer"].append(tag)
        elif abs(z) < tol:
            faces["hole_mouth"].append(tag)
        elif abs(z + depth) < tol:
            faces["hole_bottom"].append(tag)
        elif abs(z + depth + bt) < tol:
            faces["support"] += [] if support else [tag]
        elif support:
            faces["support"].append(tag)
    return volume[1], faces


def _peg(scene: dict) -> tuple[int, dict]:
    """The placed peg volume and its faces by tag name."""
    import gmsh

    peg, occ, pose = scene["peg"], gmsh.model.occ, peg_pose(scene)
    d, length, cw = peg["width"], peg["length"], peg["chamfer_width"]
    h_p = chamfer_height(cw, peg["chamfer_angle"])
    parts = [(3, occ.addCylinder(0, 0, h_p, 0, 0, length - h_p, d / 2))]
    if cw > 0:
        parts.append((3, occ.addCone(0, 0, 0, 0, 0, h_p, d / 2 - cw, d / 2)))
        parts, _ = occ.fuse(parts[:1], parts[1:])
    # local z (the peg axis) -> (-sin(tilt), 0, cos(tilt)): rotation by -tilt about y
    occ.rotate(parts, 0, 0, 0, 0, 1, 0, -pose.tilt)
    occ.translate(parts, *pose.origin)
    occ.synchronize()
    faces = {"peg_side": [], "peg_tip": [], "peg_top": [], "peg_chamfer": []}
    for _, tag in gmsh.model.getBoundary(parts, oriented=False):
        kind = gmsh.model.getType(2, tag)
        eta = (np.array(occ.getCenterOfMass(2, tag)) - pose.origin) @ pose.rotation[:, 2]
        if kind == "Cylinder":
            faces["peg_side"].append(tag)
        elif kind == "Cone":
            faces["peg_chamfer"].append(tag)
        else:
            faces["peg_tip" if eta < length / 2 else "peg_top"].append(tag)
    return parts[0][1], faces


def generate(scene: dict, sz: gmsh_tools.Sizes) -> dict:
    """Build and mesh the gmsh model (current gmsh model, this rank only); returns the names."""
    import gmsh

    if scene["rigid"] == "peg":
        volume, faces = _hole_block(scene)
        cell, supports = "block", ["support"]
        contact = ["hole_wall", "hole_mouth", "hole_chamfer"]
        round_faces = [n for n in ("hole_wall", "hole_chamfer") if faces[n]]
        revolution = {"facets": round_faces, "point": [0.0, 0.0, 0.0], "direction": [0.0, 0.0, 1.0]}
    else:
        volume, faces = _peg(scene)
        cell, supports = "peg", ["peg_top"]  # held by the gripper
        contact = ["peg_side", "peg_tip", "peg_chamfer"]
        revolution = {}
    points = peg_pose(scene).points
    gmsh_tools.background([gmsh_tools.ball_size(sz, points[name], sz.zone) for name in ("contact_A", "contact_B")])
    cells = gmsh_tools.add_groups(3, {cell: [volume]})
    facets = gmsh_tools.add_groups(2, faces)
    gmsh.option.setNumber("Mesh.OptimizeThreshold", 0.45)  # optimise tetrahedra of quality below this
    gmsh.model.mesh.generate(3)
    return {"facets": facets, "cells": cells, "contact_facets": [n for n in contact if n in facets],
            "supports": supports, "revolution": revolution}
