"""Inertia by Newmark time integration: the rigid body always, the deformable body with
`dynamics.deformable_inertia` (mass density of its material, t/mm^3).

The rigid body's equations gain M a(r) with a from Newmark (M: mass and moments of
inertia about the reference point); the deformable body's residual gains rho a(u) . v.
It is the problem's `time_stepping`. `scheme = "euler"` (set by femcontact.solver.dynamics) makes the rigid body's term
implicit Euler, M (v1 - v0) / dt with v1 = (r - r_old) / dt; `active = False` switches
the rigid body's inertia off (quasi-static steps before a dynamic phase).
"""
import numpy as np
import ufl
from dolfinx import fem

from femcontact.effects.base import Effect
from femcontact.physics import newmark


class Inertia(Effect):
    name = "inertia"

    def __init__(self, problem):
        super().__init__(problem)
        dynamics = problem.scene["dynamics"]
        self.beta, self.gamma = dynamics["newmark_beta"], dynamics["newmark_gamma"]
        self.deformable = dynamics["deformable_inertia"]
        n = len(problem.rigid.names)
        self.velocity, self.acceleration = np.zeros(n), np.zeros(n)  # rigid body (mm/s, mm/s^2; rad)
        self.dt = 1.0
        self.scheme, self.active = "newmark", True

    def constants(self, scene: dict, body: str) -> dict:
        if not self.deformable:
            return {}
        return {"density": scene["materials"][body]["density"], "beta": self.beta, "dt": 1.0}

    def build(self, problem) -> None:
        problem.time_stepping = self  # what solver/dynamics.py integrates in time
        self.fields = {}
        if not self.deformable:
            return
        self.fields = {name: fem.Function(problem.V, name=name) for name in ("u_old", "v_old", "a_old")}
        c, f = problem.constants, self.fields
        a = newmark.acceleration(problem.u, f["u_old"], f["v_old"], f["a_old"], c["dt"], c["beta"])
        problem.add_bulk(c["density"] * ufl.dot(a, problem.v))

    def begin_increment(self, load) -> None:
        self.dt = load.dt
        if self.deformable:
            self.problem.constants["dt"].value = load.dt

    def _rigid_acceleration(self) -> np.ndarray:
        rigid = self.problem.rigid
        return newmark.acceleration(rigid.values, rigid.r_old.value, self.velocity, self.acceleration,
                                    self.dt, self.beta)

    def _euler_velocity(self) -> np.ndarray:
        rigid = self.problem.rigid
        return (rigid.values - rigid.r_old.value) / self.dt

    def rigid_residual(self, load) -> np.ndarray | None:
        """M a(r) (N, N*mm) for the current pose (Euler: M (v1 - v0) / dt)."""
        if not self.active:
            return None
        if self.scheme == "euler":
            return self.problem.rigid.mass_matrix @ (self._euler_velocity() - self.velocity) / self.dt
        return self.problem.rigid.mass_matrix @ self._rigid_acceleration()

    def rigid_stiffness(self, load) -> np.ndarray | None:
        if not self.active:
            return None
        return self.problem.rigid.mass_matrix / ((1.0 if self.scheme == "euler" else self.beta) * self.dt ** 2)

    def commit(self, dt: float) -> None:
        if not self.active:
            self.velocity[:], self.acceleration[:] = 0.0, 0.0
        elif self.scheme == "euler":
            v = self._euler_velocity()
            self.velocity, self.acceleration = v, (v - self.velocity) / dt
        else:
            a = self._rigid_acceleration()
            self.velocity = newmark.velocity(self.velocity, self.acceleration, a, dt, self.gamma)
            self.acceleration = a
        if self.deformable:
            u, u_old, v_old, a_old = (self.problem.u.x.array, *(self.fields[k].x.array for k in ("u_old", "v_old", "a_old")))
            a = newmark.acceleration(u, u_old, v_old, a_old, dt, self.beta)
            v_old[:] = newmark.velocity(v_old, a_old, a, dt, self.gamma)
            a_old[:] = a
            u_old[:] = u

    def state(self) -> dict:
        return {"velocity": self.velocity.copy(), "acceleration": self.acceleration.copy(),
                **{name: f.x.array.copy() for name, f in self.fields.items()}}

    def restore(self, state: dict) -> None:
        self.velocity[:], self.acceleration[:] = state["velocity"], state["acceleration"]
        for name, f in self.fields.items():
            f.x.array[:] = state[name]
