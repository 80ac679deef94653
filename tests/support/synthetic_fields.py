"""Synthetic `fields.npz` files (the format `femcontact.outputs.snapshot.render` reads), for tests.

A block under a pressed rigid disc: structured triangles (2-D) or tetrahedra (3-D),
von Mises = 100 / (1 + r^2) around the contact point (0, 0(, 0)) (or, `singular`, a corner
singularity 1 / (r + 1e-4) with its peak 1e4 at that one node), a displacement that
dents the top face, the disc outline as `rigid_outline` and `contact_A` as a named point.
"""
import itertools

import numpy as np


def block_mesh(dim: int, n: int = 12):
    """Points (N x 3) and cells (triangles or Kuhn tetrahedra) of the block [-5, 5] x [-5, 0](x [-5, 5])."""
    axes = [np.linspace(-5, 5, n + 1), np.linspace(-5, 0, n // 2 + 1)] + ([np.linspace(-5, 5, n + 1)] if dim == 3 else [])
    shape = [len(a) for a in axes]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, dim)
    points = np.zeros((len(grid), 3))
    points[:, :dim] = grid
    index = np.arange(len(grid)).reshape(shape)
    cells = []
    for corner in itertools.product(*(range(s - 1) for s in shape)):
        if dim == 2:
            i, j = corner
            a, b, c, d = index[i, j], index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]
            cells += [(a, b, c), (a, c, d)]
        else:
            for order in itertools.permutations(range(3)):  # Kuhn: 6 tetrahedra per cube
                vertex, path = list(corner), [index[corner]]
                for axis in order:
                    vertex[axis] += 1
                    path.append(index[tuple(vertex)])
                cells.append(tuple(path))
    return points, np.array(cells, dtype=np.int64)


def write_fields(path, dim: int = 2, cellwise: bool = False, singular: bool = False) -> np.ndarray:
    """Write a synthetic fields.npz; returns the von Mises array written."""
    points, cells = block_mesh(dim)
    r2 = (points ** 2).sum(axis=1)
    nodal = 1.0 / (np.sqrt(r2) + 1e-4) if singular else 100.0 / (1.0 + r2)
    von_mises = nodal[cells].mean(axis=1) if cellwise else nodal
    displacement = np.zeros_like(points)
    displacement[:, 1] = -0.2 * np.exp(-r2 / 4)
    angle = np.linspace(0, 2 * np.pi, 65)
    outline = np.stack([3 * np.sin(angle), 3 - 0.2 + 3 * np.cos(angle), np.zeros_like(angle)], axis=1)
    np.savez(path, points=points, cells=cells, cell_type="triangle" if dim == 2 else "tetra",
             displacement=displacement, von_mises=von_mises, rigid_outline=outline,
             named_point_names=np.array(["contact_A"]), named_point_coords=np.zeros((1, 3)))
    return von_mises
