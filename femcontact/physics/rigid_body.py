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

from femcontact.physics.rotation import rotation_numpy, rotation_ufl
from femcontact.physics.signed_distance import reference_point
from femcontact.physics.dofs import RIGID_DOFS


def mass_properties(rigid: dict, density: float, dim: int):
    """Mass (t) and principal moments of inertia about the reference point (t*mm^2) of a
    rigid shape of `density` (t/mm^3); a 2-D body has unit thickness (1 mm), like its loads."""
    shape = rigid["shape"]
    if shape == "rectangle":
        w, h = 2 * rigid["half_width"], rigid["length"]
        m = density * w * h
        return m, np.array([m * (w * w + h * h) / 12])
    if shape == "disc":
        m = density * np.pi * rigid["radius"] ** 2
        return m, np.array([m * rigid["radius"] ** 2 / 2])
    if shape == "pin":  # polygon of its outline (arcs sampled), reference point at the tip centre
        from femcontact.physics.signed_distance import outline

        x, y = outline(rigid)[:, :2].T
        cross = x[:-1] * y[1:] - x[1:] * y[:-1]
        area = cross.sum() / 2
        xx = (cross * (x[:-1] ** 2 + x[:-1] * x[1:] + x[1:] ** 2)).sum() / 12  # integral of x^2 (mm^4)
        yy = (cross * (y[:-1] ** 2 + y[:-1] * y[1:] + y[1:] ** 2)).sum() / 12
        m = density * area
        if dim == 2:
            return m, np.array([density * (xx + yy)])
        # 3-D blade: the section 1 mm thick about z = 0 (x and y axes through the tip centre)
        return m, np.array([density * yy + m / 12, density * xx + m / 12, density * (xx + yy)])
    if shape == "sphere":
        m = density * 4 / 3 * np.pi * rigid["radius"] ** 3
        return m, np.full(3, 0.4 * m * rigid["radius"] ** 2)
    if shape == "cylinder":
        R, L = rigid["radius"], rigid["length"]
        m = density * np.pi * R * R * L
        side = m * (3 * R * R + L * L) / 12
        return m, np.array([side, side, m * R * R / 2])
    return 0.0, np.zeros(1 if dim == 2 else 3)


def scene_rigid_body(scene: dict, mesh, rigid: dict) -> "RigidBody":
    """The scene's rigid body of shape `rigid` on `mesh`: its dofs (`rigid_body.dofs`) and its mass
    from its shape and the density of its material, or `rigid_body.mass` (t) when given (the
    moments of the uniform shape scaled alike)."""
    dim = mesh.geometry.dim
    mass, moments = mass_properties(rigid, scene["materials"][scene["rigid"]]["density"], dim)
    given = scene["rigid_body"]["mass"]
    if given:
        moments = moments * given / mass if mass else moments
        mass = given
    return RigidBody(mesh, rigid, scene["rigid_body"]["dofs"], mass, moments)


class RigidBody:
    """Pose unknowns of the rigid body, their UFL images and its mass.

    `r` is a Constant wrapped in a ufl.variable so forms can be differentiated with
    respect to the pose; `r_old` holds the pose at the last converged increment.
    `mass` (t) and `mass_matrix` (t, t*mm^2) are used only by effects that need them."""

    def __init__(self, mesh, rigid: dict, modes: dict, mass: float, moments: np.ndarray):
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
        self.mass_matrix = np.diag(np.r_[[mass] * self.dim, moments])

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

    def to_local_direction(self, a, r):
        """Rotate a spatial vector a into the shape frame (UFL)."""
        _, angles = self.split(r)
        return self.Q0_constant.T * rotation_ufl(angles).T * a

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
