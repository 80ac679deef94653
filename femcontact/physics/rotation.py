"""Rotations of the rigid body: 2-D angle [rz]; 3-D Rz(rz) Ry(ry) Rx(rx) for [rx, ry, rz] (rad).

One formula, written once over a small namespace so that the numpy matrix and the UFL
matrix (for forms differentiated with respect to the pose) cannot drift apart.
"""
import numpy as np


def _rotation(angles, cos, sin, matrix, product):
    if len(angles) == 1:
        c, s = cos(angles[0]), sin(angles[0])
        return matrix([[c, -s], [s, c]])
    rx, ry, rz = angles
    Rx = matrix([[1, 0, 0], [0, cos(rx), -sin(rx)], [0, sin(rx), cos(rx)]])
    Ry = matrix([[cos(ry), 0, sin(ry)], [0, 1, 0], [-sin(ry), 0, cos(ry)]])
    Rz = matrix([[cos(rz), -sin(rz), 0], [sin(rz), cos(rz), 0], [0, 0, 1]])
    return product(product(Rz, Ry), Rx)


def rotation_numpy(angles) -> np.ndarray:
    """Rotation matrix (numpy) for 2-D [rz] or 3-D [rx, ry, rz]."""
    return _rotation(angles, np.cos, np.sin, lambda rows: np.array(rows, dtype=float), np.matmul)


def rotation_ufl(angles):
    """The same rotation as a UFL matrix of UFL scalars."""
    import ufl  # here, so the truss model (numpy only) never imports UFL

    return _rotation(angles, ufl.cos, ufl.sin, ufl.as_matrix, lambda a, b: a * b)


def cross_axis(k: int, arms: np.ndarray) -> np.ndarray:
    """e_k x arm for each row (2-D arms use k = 2, the out-of-plane axis)."""
    if arms.shape[1] == 2:
        return np.c_[-arms[:, 1], arms[:, 0]]
    e = np.zeros(3)
    e[k] = 1.0
    return np.cross(e, arms)


def cross_with_axis(a: np.ndarray, k: int) -> np.ndarray:
    """a x e_k for each row (2-D: k = 2), the gradient of C . (e_k x d) with respect to d."""
    if a.shape[1] == 2:
        return np.c_[a[:, 1], -a[:, 0]]
    e = np.zeros(3)
    e[k] = 1.0
    return np.cross(a, e)


def rigid_modes(arms: np.ndarray) -> list[np.ndarray]:
    """Rigid-body motions of points at `arms` (n x dim, mm from the centre): translations,
    then rotations e_k x arm (one in 2-D, three in 3-D); each an (n x dim) array."""
    dim = arms.shape[1]
    modes = []
    for k in range(dim):
        mode = np.zeros_like(arms)
        mode[:, k] = 1.0
        modes.append(mode)
    for k in [2] if dim == 2 else [0, 1, 2]:
        modes.append(cross_axis(k, arms))
    return modes
