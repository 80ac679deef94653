"""Load steps: amplitudes in time and the external load on the rigid body.

A step names the force (N) and moment (N*mm) on the rigid body and the prescribed
rigid motion (mm, rad) at its end. 'ramp' goes linearly from the values at the end of
the previous step, 'step' applies them at once, 'pulse' multiplies them by a pulse
train (frequency Hz, duty fraction, triangle/square/haversine shape).
"""
from dataclasses import dataclass

import numpy as np

from femcontact.physics.dofs import RIGID_DOFS
from femcontact.physics.rotation import rotation_numpy


def pulse(t: float, frequency: float, duty: float, shape: str) -> float:
    """Pulse train value in [0, 1] at time t (s) since the start of the step."""
    phase = (t * frequency) % 1.0
    if phase >= duty:
        return 0.0
    x = phase / duty
    return {"triangle": 1 - abs(2 * x - 1), "square": 1.0, "haversine": np.sin(np.pi * x) ** 2}[shape]


@dataclass
class Load:
    """External load and prescribed motion at one instant."""
    step: int
    time: float          # s since the start of the simulation
    dt: float            # s, length of the increment ending at `time`
    force: np.ndarray    # N, on the rigid body at `point`
    moment: np.ndarray   # N*mm (1 component in 2-D, 3 in 3-D)
    point: np.ndarray    # load point in the rigid body's shape frame (mm, about its reference point)
    motion: np.ndarray   # prescribed values of the rigid dofs (mm, rad); used for non-free dofs
    rigid: object        # the RigidBody (pose maps)

    def generalized_force(self, r: np.ndarray) -> np.ndarray:
        """Force and moment about the current reference point for pose r."""
        dim = len(self.force)
        arm = rotation_numpy(self.rigid.split(r)[1]) @ self.rigid.Q0 @ self.point
        if dim == 2:
            moment = self.moment[0] + arm[0] * self.force[1] - arm[1] * self.force[0]
            return np.r_[self.force, moment]
        return np.r_[self.force, self.moment + np.cross(arm, self.force)]

    def generalized_force_jacobian(self, r: np.ndarray, h: float = 1e-7) -> np.ndarray:
        """d(generalized_force)/dr by central differences (the map is smooth)."""
        n = len(r)
        J = np.zeros((n, n))
        for k in range(n):
            e = np.zeros(n)
            e[k] = h
            J[:, k] = (self.generalized_force(r + e) - self.generalized_force(r - e)) / (2 * h)
        return J


class Schedule:
    """Turns the scene's steps into `Load`s at any time inside a step."""

    def __init__(self, scene: dict, rigid, points_local: dict):
        self.steps = scene["steps"]
        self.rigid, self.points = rigid, points_local
        dim = scene["dim"]
        self.names = RIGID_DOFS[dim]
        zero = {"force": np.zeros(dim), "moment": np.zeros(1 if dim == 2 else 3), "motion": np.zeros(len(self.names))}
        self.start_values = []
        previous = zero
        for step in self.steps:
            target = {"force": np.array(step["force"]) if step["force"] else zero["force"],
                      "moment": np.array(step["moment"]) if step["moment"] else zero["moment"],
                      "motion": np.array([step["motion"][name] for name in self.names])}
            self.start_values.append((previous, target))
            previous = target if step["amplitude"] != "pulse" else {k: v * self._factor(step, step["duration"])
                                                                    for k, v in target.items()}
        self.start_times = np.cumsum([0.0] + [s["duration"] for s in self.steps])

    @staticmethod
    def _factor(step: dict, t: float) -> float:
        if step["amplitude"] == "pulse":
            return pulse(t, **step["pulse"])
        return 1.0 if step["amplitude"] == "step" else t / step["duration"]

    def load(self, index: int, t: float, dt: float) -> Load:
        """Load in step `index` at time t (s) since the step began."""
        step = self.steps[index]
        start, target = self.start_values[index]
        f = self._factor(step, t)
        value = {k: target[k] * f if step["amplitude"] == "pulse" else start[k] + f * (target[k] - start[k])
                 for k in target}
        if step["load_point"] not in self.points:
            from femcontact.errors import InputError
            raise InputError(f"steps[{index}].load_point = {step['load_point']!r}: unknown point, "
                             f"expected one of {', '.join(sorted(self.points))}")
        return Load(index, self.start_times[index] + t, dt, value["force"], value["moment"],
                    self.points[step["load_point"]], value["motion"], self.rigid)
