"""Geometric measures of a built Model: sizes of tagged regions and element quality.

All results are global (summed over the mesh's communicator).
"""
import numpy as np


def cell_coordinates(mesh) -> np.ndarray:
    """Vertex coordinates of the locally owned cells, shape (cells, vertices, gdim) (mm).
    Affine (degree-1) geometry."""
    tdim = mesh.topology.dim
    owned = mesh.topology.index_map(tdim).size_local
    dofs = mesh.geometry.dofmap.array.reshape(-1, tdim + 1)[:owned]
    return mesh.geometry.x[dofs][:, :, :mesh.geometry.dim]


def radius_ratio(mesh) -> np.ndarray:
    """Radius ratio of each owned simplex: d * r_inscribed / r_circumscribed for dimension d,
    1 for the equilateral triangle / regular tetrahedron, 0 for a degenerate one."""
    x = cell_coordinates(mesh)
    if mesh.topology.dim == 2:
        a = np.linalg.norm(x[:, 1] - x[:, 2], axis=1)
        b = np.linalg.norm(x[:, 2] - x[:, 0], axis=1)
        c = np.linalg.norm(x[:, 0] - x[:, 1], axis=1)
        e1, e2 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
        area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
        # r_in = 2A/(a+b+c), r_circ = abc/(4A)
        return 16 * area**2 / (a * b * c * (a + b + c))
    e = x[:, 1:] - x[:, :1]  # edges from vertex 0, (cells, 3, 3)
    a, b, c = e[:, 0], e[:, 1], e[:, 2]
    six_volume = np.abs(np.einsum("ij,ij->i", a, np.cross(b, c)))
    faces = [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)]
    area = sum(0.5 * np.linalg.norm(np.cross(x[:, j] - x[:, i], x[:, k] - x[:, i]), axis=1) for i, j, k in faces)
    r_in = 0.5 * six_volume / area  # 3V / total face area
    centre = (np.sum(a * a, 1)[:, None] * np.cross(b, c) + np.sum(b * b, 1)[:, None] * np.cross(c, a)
              + np.sum(c * c, 1)[:, None] * np.cross(a, b)) / six_volume[:, None] / 2
    return 3 * r_in / np.linalg.norm(centre, axis=1)


def min_quality(mesh) -> float:
    """Smallest radius ratio over the whole (distributed) mesh."""
    from mpi4py import MPI

    q = radius_ratio(mesh)
    return mesh.comm.allreduce(float(q.min()) if q.size else 1.0, op=MPI.MIN)


def _simplex_measure(x: np.ndarray) -> np.ndarray:
    """Length/area/volume of simplices given by vertex coordinates x (simplices, vertices, 3)."""
    e = x[:, 1:] - x[:, :1]
    if e.shape[1] == 1:
        return np.linalg.norm(e[:, 0], axis=1)
    if e.shape[1] == 2:
        return 0.5 * np.linalg.norm(np.cross(e[:, 0], e[:, 1]), axis=1)
    return np.abs(np.einsum("ij,ij->i", e[:, 0], np.cross(e[:, 1], e[:, 2]))) / 6


def measure(model, facet: str | None = None, cell: str | None = None) -> float:
    """Global length/area/volume (mm^d) of the named facet tag, the named cell tag, or the
    whole mesh when neither is given (affine geometry; each entity counted on its owner)."""
    from dolfinx.cpp.mesh import entities_to_geometry
    from mpi4py import MPI

    mesh = model.mesh
    dim = mesh.topology.dim - (facet is not None)
    owned = mesh.topology.index_map(dim).size_local
    if facet is not None:
        entities = model.facet_tags.find(model.facets[facet])
    elif cell is not None:
        entities = model.cell_tags.find(model.cells[cell])
    else:
        entities = np.arange(owned, dtype=np.int32)
    entities = entities[entities < owned]
    nodes = entities_to_geometry(mesh._mesh, dim, entities, False)  # the C++ mesh in DOLFINx 0.5
    x = mesh.geometry.x[nodes].reshape(len(entities), dim + 1, 3)
    return mesh.comm.allreduce(float(_simplex_measure(x).sum()), op=MPI.SUM)
