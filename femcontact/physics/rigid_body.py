"""The rigid body: its degrees of freedom, pose and the map into its own frame.

Unknowns r (mm, rad): 2-D (x, y, rz); 3-D (x, y, z, rx, ry, rz): the translation of
the reference point and rotation angles, the rotation being Rz(rz) Ry(ry) Rx(rx).
A point with shape-frame coordinates xi sits at  p0 + t + R(r) Q0 xi  where p0 is
the initial reference point and Q0 the initial orientation (local -> global).
Each dof is 'free' (driven by loads), 'held' or 'prescribed' (driven by steps.motion).
"""
import numpy as np
import ufl
from dolfinx import fem

from femcontact.obstacle import reference_point
from femcontact.scene import RIGID_DOFS


def rotation_numpy(angles) -> np.ndarray:
    """Rotation matrix: 2-D angle [rz], or 3-D Rz Ry Rx for [rx, ry, rz]."""
    if len(angles) == 1:
        c, s = np.cos(angles[0]), np.sin(angles[0])
        return np.array([[c, -s], [s, c]])
    rx, ry, rz = angles
    Rx = np.array([[1, 0, 0], [0, np.cos(rx), -np.sin(rx)], [0, np.sin(rx), np.cos(rx)]])
    Ry = np.array([[np.cos(ry), 0, np.sin(ry)], [0, 1, 0], [-np.sin(ry), 0, np.cos(ry)]])
    Rz = np.array([[np.cos(rz), -np.sin(rz), 0], [np.sin(rz), np.cos(rz), 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def rotation_ufl(angles):
    """The same rotation as a UFL matrix of UFL scalars."""
    if len(angles) == 1:
        c, s = ufl.cos(angles[0]), ufl.sin(angles[0])
        return ufl.as_matrix([[c, -s], [s, c]])
    rx, ry, rz = angles
    Rx = ufl.as_matrix([[1, 0, 0], [0, ufl.cos(rx), -ufl.sin(rx)], [0, ufl.sin(rx), ufl.cos(rx)]])
    Ry = ufl.as_matrix([[ufl.cos(ry), 0, ufl.sin(ry)], [0, 1, 0], [-ufl.sin(ry), 0, ufl.cos(ry)]])
    Rz = ufl.as_matrix([[ufl.cos(rz), -ufl.sin(rz), 0], [ufl.sin(rz), ufl.cos(rz), 0], [0, 0, 1]])
    return Rz * Ry * Rx


class RigidBody:
    """Pose unknowns of the rigid body and their UFL images.

    `r` is a Constant wrapped in a ufl.variable so forms can be differentiated with
    respect to the pose; `r_old` holds the pose at the last converged increment."""

    def __init__(self, mesh, rigid: dict, modes: dict, mass: float):
        self.shape = rigid
        self.dim = mesh.geometry.dim
        self.names = RIGID_DOFS[self.dim]
        self.modes = [modes[name] for name in self.names]
        self.Q0 = np.asarray(rigid["rotation"], dtype=float)
        self.p0 = np.asarray(rigid["origin"], dtype=float) + self.Q0 @ reference_point(rigid)
        # the initial pose enters the forms as Constants: a sweep of placements reuses them
        self.Q0_constant = fem.Constant(mesh, self.Q0)
        self.p0_constant = fem.Constant(mesh, self.p0)
        self.values = np.zeros(len(self.names))
        self.r = fem.Constant(mesh, self.values.copy())
        self.r_old = fem.Constant(mesh, self.values.copy())
        self.variable = ufl.variable(self.r)
        self.mass = mass

    @property
    def free(self) -> np.ndarray:
        return np.array([mode == "free" for mode in self.modes])

    def split(self, r):
        """(translation, rotation angles) of a UFL or numpy pose vector."""
        d = self.dim
        angles = [r[2]] if d == 2 else [r[3], r[4], r[5]]
        return [r[i] for i in range(d)], angles

    def to_local(self, x, r):
        """Shape-frame coordinates of spatial points x for the UFL pose r."""
        t, angles = self.split(r)
        R = rotation_ufl(angles)
        return self.Q0_constant.T * R.T * (x - self.p0_constant - ufl.as_vector(t))

    def to_global_direction(self, a, r):
        """Rotate a shape-frame vector a into the spatial frame (UFL)."""
        _, angles = self.split(r)
        return rotation_ufl(angles) * self.Q0_constant * a

    def reference_point(self, values=None) -> np.ndarray:
        """Current reference point (mm)."""
        values = self.values if values is None else values
        return self.p0 + values[: self.dim]

    def place(self, local_point, values=None) -> np.ndarray:
        """Spatial position of a point given in the tip-centred local frame of the shape."""
        values = self.values if values is None else values
        t, angles = self.split(values)
        offset = np.asarray(local_point, float) - reference_point(self.shape)
        return self.p0 + np.asarray(t) + rotation_numpy(angles) @ self.Q0 @ offset

    def tilt(self, values=None) -> float:
        """Angle between the shape's axis and the global vertical (rad, signed in 2-D)."""
        values = self.values if values is None else values
        axis = rotation_numpy(self.split(values)[1]) @ self.Q0[:, -1]
        if self.dim == 2:
            return float(np.arctan2(-axis[0], axis[1]))
        return float(np.arccos(np.clip(axis[2], -1, 1)))

    def sync(self) -> None:
        """Copy the numpy pose into the form Constant."""
        self.r.value[:] = self.values

    def commit(self) -> None:
        """Accept the current pose as the converged one (history for friction)."""
        self.r_old.value[:] = self.values
