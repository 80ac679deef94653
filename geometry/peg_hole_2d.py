"""2-D peg-in-hole section (frames and placement: geometry/placement.py).

Only the deformable body is meshed: the hole block(s) when the peg is rigid, the
placed peg when the hole is rigid. Hole kinds: 'two_blocks', block A = [-D/2 - bw, -D/2]
x [-depth, 0] and block B its mirror; 'single', one U-shaped block [-D/2 - bw, D/2 + bw]
x [-depth - bottom_thickness, 0] minus the hole. Fine zones (size h_contact) are the
boundary stretches within `zone` of where contact can happen: on the blocks, the lower
mouth corners (below the chamfers) and both walls around the depth of the peg's tip
corner; on a meshed peg, both sides around l_d and the tip corners. The size grows
linearly with the distance to them (gmsh_tools.GRADING) up to the maximum size.
"""
import math

import numpy as np

from geometry import gmsh_tools
from geometry.placement import chamfer_height, peg_pose

ALL = [(-math.inf, math.inf)]


def sizes(scene: dict) -> gmsh_tools.Sizes:
    """Default sizes from a length scale s: contact size s/250, max size s/5, zone s/10, with
    s = min(block_width, depth) for meshed blocks, min(width, length) for a meshed peg."""
    scale = gmsh_tools.meshed_scale(scene)
    return gmsh_tools.sizes(scene["mesh"], scale / 250, scale / 5, scale / 10)


class _Outline:
    """Closed polygon assembled from straight runs, each with a tag name and fine stretches."""

    def __init__(self, h_contact: float):
        self.vertices, self.edges, self.h = [], [], h_contact

    def run(self, start, stop, name=None, fine=()):
        """Add the run start -> stop (stop is the next run's start). `fine`: intervals of the
        run's main coordinate (x for a horizontal run, y for a vertical one) that are fine
        zones; the run is split at their ends, but never into pieces shorter than h/2."""
        start, stop = np.asarray(start, float), np.asarray(stop, float)
        axis = int(np.argmax(np.abs(stop - start)))
        span = stop[axis] - start[axis]
        length = float(np.linalg.norm(stop - start))
        intervals = [sorted(((a - start[axis]) / span, (b - start[axis]) / span)) for a, b in fine]
        cuts = [0.0]
        for t in sorted(t for interval in intervals for t in interval if 0 < t < 1):
            if (t - cuts[-1]) * length > self.h / 2 and (1 - t) * length > self.h / 2:
                cuts.append(t)
        for a, b in zip(cuts, cuts[1:] + [1.0]):
            self.vertices.append(tuple(start + a * (stop - start)))
            middle = (a + b) / 2
            self.edges.append((name, any(lo < middle < hi for lo, hi in intervals)))

    def surface(self, lines: dict, fine: list) -> int:
        """Build the plane surface; collect line tags per name into `lines`, fine ones into `fine`."""
        surface, edges = gmsh_tools.polygon(self.vertices, self.edges)
        for name, is_fine, tag in edges:
            if name:
                lines.setdefault(name, []).append(tag)
            if is_fine:
                fine.append(tag)
        return surface


def _hole_outlines(scene: dict, sz: gmsh_tools.Sizes) -> dict[str, _Outline]:
    """Cell name -> outline of the hole block(s)."""
    hole = scene["hole"]
    D, bw, depth, bt = hole["width"], hole["block_width"], hole["depth"], hole["bottom_thickness"]
    cw, h_c, zone = hole["chamfer_width"], chamfer_height(hole["chamfer_width"], hole["chamfer_angle"]), sz.zone
    y_tip = peg_pose(scene).points["contact_B"][1]
    # the wall is split at y_tip so a mesh node sits where the peg's tip corner touches
    wall_fine = [(-h_c - zone, -h_c), (y_tip - zone, y_tip), (y_tip, y_tip + zone)]
    outer = hole["support"] == "outer"
    h = sz.h_contact

    def mouth(outline, s, label):
        """Run up wall s (-1: A, +1: B) from the hole bottom, the chamfer and the mouth, mirrored
        for s = +1 so that the outline is walked in one direction."""
        x, corner, rim = s * D / 2, (s * D / 2, -h_c), (s * (D / 2 + cw), 0.0)
        runs = [((x, -depth), corner, f"wall_{label}", wall_fine)]
        if cw > 0:
            runs.append((corner, rim, f"chamfer_{label}", ALL))
        runs.append((rim, (s * (D / 2 + bw), 0.0), f"mouth_{label}", [(s * (D / 2 + cw), s * (D / 2 + cw + zone))]))
        if s > 0:  # walk B the other way: outer edge -> mouth -> chamfer -> wall -> bottom
            runs = [(b, a, name, fine) for a, b, name, fine in reversed(runs)]
        for a, b, name, fine in runs:
            outline.run(a, b, name, fine)

    if hole["kind"] == "two_blocks":
        outlines = {}
        for s, label in ((-1, "A"), (1, "B")):
            outline = _Outline(h)
            x_out = s * (D / 2 + bw)
            if s < 0:
                outline.run((x_out, -depth), (-D / 2, -depth), None if outer else "support_A")
                mouth(outline, s, label)
                outline.run((x_out, 0.0), (x_out, -depth), "support_A" if outer else None)
            else:
                outline.run((x_out, -depth), (x_out, 0.0), "support_B" if outer else None)
                mouth(outline, s, label)
                outline.run((D / 2, -depth), (x_out, -depth), None if outer else "support_B")
            outlines[f"block_{label}"] = outline
        return outlines
    outline = _Outline(h)
    x_out, y_bot = D / 2 + bw, -depth - bt
    outline.run((-x_out, y_bot), (0.0, y_bot), None if outer else "support_A")
    outline.run((0.0, y_bot), (x_out, y_bot), None if outer else "support_B")
    outline.run((x_out, y_bot), (x_out, 0.0), "support_B" if outer else None)
    mouth(outline, 1, "B")
    outline.run((D / 2, -depth), (-D / 2, -depth), "hole_bottom")
    mouth(outline, -1, "A")
    outline.run((-x_out, 0.0), (-x_out, y_bot), "support_A" if outer else None)
    return {"block": outline}


def _peg_outline(scene: dict, sz: gmsh_tools.Sizes) -> _Outline:
    """Outline of the placed peg (meshed when the hole is rigid), built in local coordinates
    (xi, eta) and mapped to global ones."""
    peg, pose = scene["peg"], peg_pose(scene)
    d, length, l_d, cw, zone = peg["width"], peg["length"], peg["insertion_depth"], peg["chamfer_width"], sz.zone
    h_p = chamfer_height(cw, peg["chamfer_angle"])
    side_fine = [(h_p, h_p + zone), (l_d - zone, l_d + zone)]
    tip_fine = [(-d / 2 + cw, -d / 2 + cw + zone), (d / 2 - cw - zone, d / 2 - cw)]
    local = [((-d / 2 + cw, 0.0), (d / 2 - cw, 0.0), "peg_tip", tip_fine)]
    if cw > 0:
        local.append(((d / 2 - cw, 0.0), (d / 2, h_p), "peg_chamfer", ALL))
    local += [((d / 2, h_p), (d / 2, length), "peg_right", side_fine),
              ((d / 2, length), (-d / 2, length), "peg_top", ()),
              ((-d / 2, length), (-d / 2, h_p), "peg_left", side_fine)]
    if cw > 0:
        local.append(((-d / 2, h_p), (-d / 2 + cw, 0.0), "peg_chamfer", ALL))
    # split in local coordinates, where each run is axis-aligned, then map the vertices
    outline = _Outline(sz.h_contact)
    for a, b, name, fine in local:
        outline.run(a, b, name, fine)
    outline.vertices = [tuple(pose.to_global(v)) for v in outline.vertices]
    return outline


def generate(scene: dict, sz: gmsh_tools.Sizes) -> dict:
    """Build and mesh the gmsh model (current gmsh model, this rank only); returns the names:
    facets/cells (name -> physical group number), contact_facets, supports."""
    import gmsh

    lines, fine, surfaces = {}, [], {}
    if scene["rigid"] == "peg":
        for name, outline in _hole_outlines(scene, sz).items():
            surfaces[name] = [outline.surface(lines, fine)]
    else:
        surfaces["peg"] = [_peg_outline(scene, sz).surface(lines, fine)]
    gmsh.model.geo.synchronize()
    longest = max(_length(tag) for tag in fine)
    gmsh_tools.background([gmsh_tools.distance_threshold(sz, curves=fine, curve_length=longest)])
    gmsh.option.setNumber("Mesh.Algorithm", 6)
    cells = gmsh_tools.add_groups(2, surfaces)
    facets = gmsh_tools.add_groups(1, {name: lines[name] for name in sorted(lines)})
    gmsh.model.mesh.generate(2)
    if scene["rigid"] == "peg":
        contact = [n for n in facets if n.split("_")[0] in ("wall", "mouth", "chamfer")]
        supports = [n for n in facets if n.startswith("support")]
    else:
        contact = [n for n in facets if n in ("peg_left", "peg_right", "peg_tip", "peg_chamfer")]
        supports = ["peg_top"]  # the gripper holds the peg top; the rigid hole carries the loads
    return {"facets": facets, "cells": cells, "contact_facets": contact, "supports": supports}


def _length(line: int) -> float:
    """Length of a straight line of the built-in kernel (mm)."""
    import gmsh

    (a, b) = [tag for _, tag in gmsh.model.getBoundary([(1, line)], oriented=False)]
    return float(np.linalg.norm(np.subtract(gmsh.model.getValue(0, a, []), gmsh.model.getValue(0, b, []))))
