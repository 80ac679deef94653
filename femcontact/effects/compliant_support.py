"""A compliant support (Whitney's gripper; an RCC): linear springs about a compliance centre.

The support holds the rigid peg at its compliance centre C, the point `support.compliance_centre`
= L_g (mm) above the peg tip on its axis. The gripper's reference point starts at C's initial
position C0 and moves by the prescribed `steps[].support_motion` g(t) = (translation, rotation),
ramped within each step like the loads. With the relative motion of the peg at C

    q = [C(r) - C0 - g_t ;  phi(r) - g_phi]      (mm, rad; phi: 2-D angle, 3-D rotation vector)

the support's wrench on the peg, force at C and moment about C (global axes, N and N*mm), is

    [F ; M_C] = -K q,

K (3x3 in 2-D for x, y, rz; 6x6 in 3-D) from `support.model`: 'springs' (diagonal kx, kz,
ktheta, ktorsion), 'matrix' (`support.stiffness`, row by row) or 'rcc' (the RCC truss design
formula at its compliance centre, femcontact.physics.rcc). K is in the global frame: x lateral,
y (2-D) / z (3-D) along the hole axis. The rigid body's equations gain -(F, M_C + (C - x_ref) x F)
and their exact derivative with respect to the pose (central differences of this smooth map),
so the peg's dofs stay 'free' and are pulled by the springs.
"""
import math

import numpy as np

from femcontact.effects.base import Effect
from femcontact.errors import InputError
from femcontact.physics.rotation import rotation_numpy
from femcontact.physics.support import stiffness_matrix


def rotation_vector(R: np.ndarray) -> np.ndarray:
    """Rotation vector (rad) of a 3-D rotation matrix (log map, angles < pi)."""
    angle = math.acos(np.clip((np.trace(R) - 1) / 2, -1.0, 1.0))
    axial = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]]) / 2
    return axial if angle < 1e-8 else axial * angle / math.sin(angle)


class CompliantSupport(Effect):
    name = "compliant_support"

    def __init__(self, problem):
        super().__init__(problem)
        scene, rigid = problem.scene, problem.rigid
        if scene.get("rigid") != "peg":
            raise InputError(f"effects: 'compliant_support' holds a rigid peg (rigid = {scene.get('rigid')!r})")
        self.dim = problem.dim
        self.K = stiffness_matrix(scene)
        self.centre_local = np.zeros(self.dim)
        self.centre_local[-1] = scene["support"]["compliance_centre"]  # tip-centred local frame
        self.centre0 = rigid.place(self.centre_local, np.zeros(len(rigid.names)))
        self.targets = [np.array([step["support_motion"][name] for name in rigid.names]) for step in scene["steps"]]
        self.start_times = np.cumsum([0.0] + [step["duration"] for step in scene["steps"]])
        self.motion = np.zeros(len(rigid.names))

    def _gripper(self, load) -> np.ndarray:
        """Prescribed gripper motion g (mm, rad) at the load's time: ramped from the previous step's end."""
        steps = self.problem.scene["steps"]
        start = self.targets[load.step - 1] if load.step > 0 else np.zeros_like(self.motion)
        step = steps[load.step]
        f = 1.0 if step["amplitude"] == "step" else (load.time - self.start_times[load.step]) / step["duration"]
        return start + min(max(f, 0.0), 1.0) * (self.targets[load.step] - start)

    def deflection(self, values: np.ndarray, motion: np.ndarray) -> np.ndarray:
        """q: the peg's motion at the compliance centre relative to the gripper (mm, rad)."""
        rigid, d = self.problem.rigid, self.dim
        centre = rigid.place(self.centre_local, values)
        angles, target = rigid.split(values)[1], rigid.split(motion)[1]
        if d == 2:
            phi = np.array([angles[0] - target[0]])
        else:
            phi = rotation_vector(rotation_numpy(angles) @ rotation_numpy(target).T)
        return np.r_[centre - self.centre0 - motion[:d], phi]

    def wrench(self, values: np.ndarray, motion: np.ndarray) -> np.ndarray:
        """Force at C and moment about C of the support on the peg (N, N*mm)."""
        return -self.K @ self.deflection(values, motion)

    def _residual(self, values: np.ndarray, motion: np.ndarray) -> np.ndarray:
        rigid, d = self.problem.rigid, self.dim
        w = self.wrench(values, motion)
        force, moment = w[:d], w[d:]
        arm = rigid.place(self.centre_local, values) - rigid.reference_point(values)
        about_reference = moment + (np.cross(arm, force) if d == 3 else arm[0] * force[1] - arm[1] * force[0])
        return -np.r_[force, about_reference]

    def rigid_residual(self, load) -> np.ndarray:
        """The support's terms for the pose; without a load (None) the gripper is at its start."""
        self.motion = self._gripper(load) if load is not None else np.zeros_like(self.motion)
        return self._residual(self.problem.rigid.values, self.motion)

    def rigid_stiffness(self, load, h: float = 1e-7) -> np.ndarray:
        motion, values = self._gripper(load), self.problem.rigid.values
        n = len(values)
        J = np.zeros((n, n))
        for k in range(n):
            e = np.zeros(n)
            e[k] = h
            J[:, k] = (self._residual(values + e, motion) - self._residual(values - e, motion)) / (2 * h)
        return J

    def outputs(self) -> dict:
        """The support's wrench on the peg at C (support_F*, support_M*), the gripper's motion
        (gripper_*), the compliance centre's deflection from it (support_q*), the tip centre
        (tip_*, mm) and in 3-D the peg's tilt in the x-z plane (tilt_xz_deg, signed as in 2-D)."""
        rigid, d = self.problem.rigid, self.dim
        q = self.deflection(rigid.values, self.motion)
        w = -self.K @ q
        axes, moments = "xyz"[:d], (["z"] if d == 2 else list("xyz"))
        row = {f"support_F{a}": float(w[k]) for k, a in enumerate(axes)}
        row.update({f"support_M{a}": float(w[d + k]) for k, a in enumerate(moments)})
        row.update({f"gripper_{name}": float(v) for name, v in zip(rigid.names, self.motion)})
        row.update({f"support_q{name}": float(v) for name, v in zip(rigid.names, q)})
        tip = rigid.place(np.zeros(d), rigid.values)
        row.update({f"tip_{a}": float(tip[k]) for k, a in enumerate(axes)})
        if d == 3:  # the tilt in the x-z plane, signed as in 2-D (top towards -x positive)
            axis = rigid.place(np.eye(3)[2], rigid.values) - tip
            row["tilt_xz_deg"] = float(np.degrees(np.arctan2(-axis[0], axis[2])))
        return row

    def load_scale(self) -> float:
        """Largest lateral spring force for the prescribed lateral gripper travel (N)."""
        d = self.dim
        lateral = [np.abs(self.K[:d - 1, :d - 1] @ t[:d - 1]).max() for t in self.targets] if self.targets else []
        return float(max(lateral + [0.0]))
