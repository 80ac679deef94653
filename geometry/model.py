"""A meshed scene: the deformable body's DOLFINx mesh with named tags, plus the rigid body.

`build(scene, comm)` dispatches on scene["geometry"], scene["dim"] and scene["rigid"] to a
builder (peg_hole_2d, peg_hole_3d, block, snap_fit). Each builder has `sizes(scene)` (computed on
every rank) and `generate(scene, sizes)` (gmsh, on rank 0 only, returning the tag names);
`rigid_body(scene)` and `points(scene)` are pure geometry, computed on every rank.
"""
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


@dataclass
class Model:
    """mesh, cell_tags, facet_tags: DOLFINx objects; facets/cells: tag name -> tag value;
    rigid: analytic description of the rigid body (docs/geometry.md); points: named global
    points (mm); contact_facets: facet tags that may touch the rigid body; supports: facet
    tags to fix; h_contact: element size in the contact zones (mm); symmetry: facet tag name
    -> the displacement component (0: x, 1: y) held on that symmetry plane; revolution: the
    contact facet tags that mesh a surface of revolution ("facets") and its axis (a "point" on it
    and its unit "direction"), empty where there is none (`contact.surface = "exact"`)."""
    mesh: object
    cell_tags: object
    facet_tags: object
    facets: dict
    cells: dict
    rigid: dict
    points: dict
    contact_facets: list
    supports: list
    h_contact: float
    symmetry: dict = field(default_factory=dict)
    revolution: dict = field(default_factory=dict)


def builder(scene: dict):
    """The builder module of a scene (block, peg_hole_2d, peg_hole_3d or snap_fit)."""
    if scene["geometry"] == "snap_fit":
        from geometry import snap_fit

        return snap_fit
    if scene["geometry"] == "block":
        from geometry import block

        return block
    if scene["dim"] == 2:
        from geometry import peg_hole_2d

        return peg_hole_2d
    from geometry import peg_hole_3d

    return peg_hole_3d


def rigid_body(scene: dict) -> dict:
    """Analytic description of the rigid body (keys: docs/geometry.md)."""
    dim = scene["dim"]
    if scene["geometry"] == "snap_fit":
        from geometry import snap_fit

        return snap_fit.rigid_body(scene)
    identity = {"origin": np.zeros(dim), "rotation": np.eye(dim), "tilt": 0.0}
    if scene["geometry"] == "block":
        ind = scene["indenter"]
        if ind["shape"] in ("cylinder", "sphere"):
            R = ind["radius"]
            shape = "disc" if dim == 2 else "cylinder_y" if ind["shape"] == "cylinder" else "sphere"
            return {**identity, "shape": shape, "radius": R, "origin": np.eye(dim)[dim - 1] * R}
        flat = {"length": ind["width"], "corner_radius": 0.0, "chamfer_width": 0.0, "chamfer_angle": 45.0}
        if dim == 2:
            return {**identity, "shape": "rectangle", "half_width": ind["width"] / 2, **flat}
        return {**identity, "shape": "cylinder", "radius": ind["width"] / 2, **flat}
    from geometry.placement import peg_pose

    if scene["rigid"] == "peg":
        peg, pose = scene["peg"], peg_pose(scene)
        size = {"half_width": peg["width"] / 2} if dim == 2 else {"radius": peg["width"] / 2}
        return {"shape": "rectangle" if dim == 2 else "cylinder", **size, "length": peg["length"],
                "corner_radius": peg["corner_radius"], "chamfer_width": peg["chamfer_width"],
                "chamfer_angle": peg["chamfer_angle"], "origin": pose.origin, "rotation": pose.rotation,
                "tilt": pose.tilt, "tip_contact": peg.get("tip_contact", True)}
    hole = scene["hole"]
    return {**identity, "shape": "hole", "half_width": hole["width"] / 2, "depth": hole["depth"],
            "block_width": hole["block_width"], "kind": hole["kind"],
            "bottom_thickness": hole["bottom_thickness"], "chamfer_width": hole["chamfer_width"],
            "chamfer_angle": hole["chamfer_angle"]}


def points(scene: dict) -> dict:
    """Named global points (mm): the peg's (placement.Pose.points) for peg_in_hole; for a
    block, `contact` (first contact point, the origin) and `indenter` (the indenter's
    reference point: cylinder axis or flat-punch tip centre); for a snap fit, snap_fit.points."""
    if scene["geometry"] == "snap_fit":
        from geometry import snap_fit

        return snap_fit.points(scene)
    if scene["geometry"] == "block":
        rigid = rigid_body(scene)
        return {"contact": np.zeros(scene["dim"]), "indenter": rigid["origin"].copy()}
    from geometry.placement import peg_pose

    return dict(peg_pose(scene).points)


def check_mesh(scene: dict) -> float:
    """Refuse a scene whose mesh would be too large or too coarse (geometry.mesh_size), before
    gmsh runs; returns the estimated number of elements."""
    from geometry import mesh_size

    return mesh_size.check(scene, builder(scene).sizes(scene))


def build(scene: dict, comm, msh_path=None) -> Model:
    """Mesh the deformable body of a resolved scene on rank 0 of `comm` and distribute it, the same
    way in every run (SCOTCH on one thread unless SCOTCH_PTHREAD_NUMBER is set: with its threads
    the cells each rank owned changed from run to run). `msh_path`: also write the gmsh mesh
    there (.msh)."""
    import gmsh
    from dolfinx.io import gmshio

    from geometry import gmsh_tools

    from geometry import mesh_size

    module = builder(scene)
    sizes = module.sizes(scene)
    mesh_size.check(scene, sizes)  # before gmsh: an absurd size would exhaust the memory or crash it
    names, error = None, None
    if comm.rank == 0:
        try:
            gmsh_tools.start(scene.get("name", "scene"))
            names = module.generate(scene, sizes)
            if scene["mesh"]["geometry_order"] == 2:
                gmsh.model.mesh.setOrder(2)  # edge midpoints onto the CAD surfaces: curved elements
            if msh_path is not None:
                gmsh.write(str(msh_path))
        except Exception as exc:  # re-raised on every rank below, so no rank waits forever
            error = exc
    error = comm.bcast(error, root=0)
    if error is not None:
        raise error
    names = comm.bcast(names, root=0)
    os.environ.setdefault("SCOTCH_PTHREAD_NUMBER", "1")
    try:
        mesh, cell_tags, facet_tags = gmshio.model_to_mesh(gmsh.model, comm, 0, gdim=scene["dim"])
    finally:
        if comm.rank == 0:
            gmsh.model.remove()
    return Model(mesh=mesh, cell_tags=cell_tags, facet_tags=facet_tags, facets=names["facets"],
                 cells=names["cells"], rigid=rigid_body(scene), points=points(scene),
                 contact_facets=names["contact_facets"], supports=names["supports"],
                 h_contact=sizes.h_contact, symmetry=names.get("symmetry", {}),
                 revolution=names.get("revolution", {}))


def write(model: Model, path) -> None:
    """Write the mesh, cell tags ("Cell tags") and facet tags ("Facet tags") to XDMF at `path`,
    and the tag names (name -> value) to the JSON file beside it (`<stem>.tags.json`)."""
    import json

    from dolfinx.io import XDMFFile

    path = Path(path)
    comm = model.mesh.comm
    with XDMFFile(comm, str(path), "w") as xdmf:
        xdmf.write_mesh(model.mesh)
        xdmf.write_meshtags(model.cell_tags)
        xdmf.write_meshtags(model.facet_tags)
    if comm.rank == 0:
        names = {"cells": model.cells, "facets": model.facets, "contact_facets": model.contact_facets,
                 "supports": model.supports, "h_contact": model.h_contact}
        path.with_suffix(".tags.json").write_text(json.dumps(names, indent=1) + "\n")
