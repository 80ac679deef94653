"""The discrete problem of a scene: function space, unknowns, effects and outputs.

`Problem` builds only what the scene's effects call for (`built` lists them) and
keeps the history states those effects need in `history` (none for a frictionless
quasi-static scene).
"""
import numpy as np
import ufl
from dolfinx import fem

from femcontact.corners import RigidCorners
from femcontact.effects import EFFECT_COMPONENTS, add_contact, add_elasticity, constants_for, make_constants
from femcontact.errors import InputError
from femcontact.rigid_body import RigidBody

SHAPE_PARAMETERS = ("half_width", "length", "radius", "corner_radius", "depth", "block_width", "bottom_thickness")


def rigid_mass(rigid: dict, density: float, dim: int):
    """Mass (t) and principal moments of inertia about the reference point (t*mm^2);
    2-D bodies have unit thickness (1 mm)."""
    shape = rigid["shape"]
    if shape == "rectangle":
        w, h = 2 * rigid["half_width"], rigid["length"]
        m = density * w * h
        return m, np.array([m * (w * w + h * h) / 12])
    if shape == "disc":
        m = density * np.pi * rigid["radius"] ** 2
        return m, np.array([m * rigid["radius"] ** 2 / 2])
    if shape == "cylinder":
        R, L = rigid["radius"], rigid["length"]
        m = density * np.pi * R * R * L
        side = m * (3 * R * R + L * L) / 12
        return m, np.array([side, side, m * R * R / 2])
    return 0.0, np.zeros(1 if dim == 2 else 3)


class Problem:
    """Unknowns, forms' ingredients and state of one scene on one mesh."""

    def __init__(self, scene: dict, model):
        self.scene, self.model = scene, model
        self.mesh, self.dim = model.mesh, model.mesh.geometry.dim
        self.effects = tuple(scene["effects"])
        if not model.supports:
            raise InputError(f"rigid = {scene['rigid']!r}: the deformable body has no support; "
                             "hold it (e.g. make the peg the rigid body)")
        deformable = {"peg": "hole", "hole": "peg", "indenter": "block"}[scene["rigid"]]
        rigid_name = "peg" if scene["rigid"] == "peg" else scene["rigid"]
        self.V = fem.VectorFunctionSpace(self.mesh, ("Lagrange", scene["mesh"]["degree"]))
        self.u = fem.Function(self.V, name="displacement")
        self.v = ufl.TestFunction(self.V)
        self.dx = ufl.Measure("dx", domain=self.mesh)
        # Contact terms use a fixed rule, so the residual and its derivatives integrate
        # alike. In 2-D it is Gauss-Lobatto on the element nodes (node-to-surface contact:
        # a penetrating corner node is seen at once); basix has no such rule on triangles,
        # so 3-D P1 uses the facet's vertices as a custom rule (the same node-to-surface
        # contact; the nodes also lie on the exact curved surface, the facets' interior
        # does not) and 3-D P2 Gauss points of degree 2p + 2.
        degree = scene["mesh"]["degree"]
        if self.dim == 2:
            quadrature = {"quadrature_rule": "GLL", "quadrature_degree": 2 * degree - 1}
        elif degree == 1:
            quadrature = {"quadrature_rule": "custom", "quadrature_degree": 1,
                          "quadrature_points": [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
                          "quadrature_weights": [1 / 6] * 3}
        else:
            quadrature = {"quadrature_degree": 2 * degree + 2}
        ds = ufl.Measure("ds", domain=self.mesh, subdomain_data=model.facet_tags, metadata=quadrature)
        self.ds_contact = ds(tuple(model.facets[name] for name in model.contact_facets))
        self.constants = make_constants(self.mesh, constants_for(scene, deformable))
        self.shape = self._shape_constants(model.rigid)
        modes = scene["rigid_body"]["dofs"]
        self.rigid = RigidBody(self.mesh, model.rigid, modes, 0.0)
        density = scene["materials"][rigid_name]["density"]
        mass, inertia = rigid_mass(model.rigid, density, self.dim)
        self.rigid.mass = scene["rigid_body"]["mass"] or mass
        self.rigid_mass_matrix = np.diag(np.r_[[self.rigid.mass] * self.dim, inertia])
        self.rigid_inertia = False
        self.history: dict[str, fem.Function] = {}
        self.bulk, self.contact_terms = [], []
        self.stick = self.slip = None

        add_elasticity(self)
        add_contact(self)
        self.built = ["elasticity", "contact"]
        for name, component in EFFECT_COMPONENTS.items():
            if name in self.effects:
                component(self)
                self.built.append(name)
        self.contact_terms.insert(0, -ufl.dot(self.traction, self.v))
        self.contact_integrand = sum(self.contact_terms)
        self.bcs = self._supports()
        self.corners = RigidCorners(self)
        if len(self.corners.points):
            self.built.append("rigid_corners")
        self.rigid_velocity = np.zeros(len(self.rigid.names))
        self.rigid_acceleration = np.zeros(len(self.rigid.names))

    def _shape_constants(self, rigid: dict) -> dict:
        """The rigid shape with its sizes as Constants, so sweeps reuse compiled forms."""
        if rigid.get("chamfer_width", 0.0) > 0:
            raise InputError(f"rigid = {self.scene['rigid']!r}: chamfers are meshed on the deformable body only; "
                             "set the rigid body's chamfer_width = 0")
        shape = dict(rigid)
        for key in SHAPE_PARAMETERS:
            if key in shape:
                shape[key] = fem.Constant(self.mesh, float(shape[key]))
        shape["scale"] = max(float(rigid.get(k, 0.0)) for k in SHAPE_PARAMETERS)
        return shape

    @property
    def support_dof_set(self) -> set:
        """Local (unrolled) indices of all supported dofs."""
        return {int(self.dim * node + k) for dofs in self.support_dofs.values() for node in dofs for k in range(self.dim)}

    def _supports(self) -> list:
        fdim = self.dim - 1
        self.support_dofs = {}
        bcs = []
        for name in self.model.supports:
            facets = self.model.facet_tags.find(self.model.facets[name])
            dofs = fem.locate_dofs_topological(self.V, fdim, facets)
            self.support_dofs[name] = dofs
            bcs.append(fem.dirichletbc(np.zeros(self.dim, dtype=np.float64), dofs, self.V))
        return bcs

    def history_function(self, name: str) -> fem.Function:
        """A history state (created on first use, shared between effects)."""
        if name not in self.history:
            self.history[name] = fem.Function(self.V, name=name)
        return self.history[name]

    def local_coordinates(self) -> np.ndarray:
        """Current position of every dof node in the rigid body's shape frame (numpy, mm)."""
        from femcontact.rigid_body import rotation_numpy

        x = self.V.tabulate_dof_coordinates()[:, : self.dim] + self.u.x.array.reshape(-1, self.dim)
        t, angles = self.rigid.split(self.rigid.values)
        R = rotation_numpy(angles) @ self.rigid.Q0
        return (x - self.rigid.p0 - np.asarray(t)) @ R

    def initialise_anchor(self) -> None:
        """Every node starts stuck where it is."""
        self.history["anchor"].x.array[:] = self.local_coordinates().reshape(-1)

    # -- rigid-body inertia (Newmark) ---------------------------------------------------
    def _newmark(self):
        d = self.scene["dynamics"]
        return d["newmark_beta"], d["newmark_gamma"]

    def _acceleration(self, x, x_old, v_old, a_old, dt: float):
        """Newmark acceleration at the end of an increment from the displacement x."""
        beta, _ = self._newmark()
        return (x - x_old - dt * v_old) / (beta * dt * dt) - (1 / (2 * beta) - 1) * a_old

    def _rigid_acceleration(self, dt: float) -> np.ndarray:
        return self._acceleration(self.rigid.values, self.rigid.r_old.value, self.rigid_velocity,
                                  self.rigid_acceleration, dt)

    def rigid_inertia_force(self, load) -> np.ndarray:
        """M a(r) (N, N*mm) for the current pose; zero without the inertia effect."""
        if not self.rigid_inertia:
            return np.zeros(len(self.rigid.names))
        return self.rigid_mass_matrix @ self._rigid_acceleration(load.dt)

    def rigid_inertia_stiffness(self, load) -> np.ndarray:
        if not self.rigid_inertia:
            return np.zeros((len(self.rigid.names),) * 2)
        beta, _ = self._newmark()
        return self.rigid_mass_matrix / (beta * load.dt ** 2)

    def set_time_step(self, dt: float) -> None:
        if "dt" in self.constants:
            self.constants["dt"].value = dt

    def commit(self, dt: float) -> None:
        """Accept the converged increment: update velocities, accelerations and history."""
        _, gamma = self._newmark()
        if self.rigid_inertia:
            a = self._rigid_acceleration(dt)
            self.rigid_velocity += dt * ((1 - gamma) * self.rigid_acceleration + gamma * a)
            self.rigid_acceleration = a
        if "a_old" in self.history:
            v_old, a_old = self.history["v_old"].x.array, self.history["a_old"].x.array
            a = self._acceleration(self.u.x.array, self.history["u_old"].x.array, v_old, a_old, dt)
            v_old[:] += dt * ((1 - gamma) * a_old + gamma * a)
            a_old[:] = a
        if "u_old" in self.history:
            self.history["u_old"].x.array[:] = self.u.x.array
        self.corners.commit()
        self.rigid.commit()

    def state(self) -> dict:
        """Copy of everything an increment changes (to retry a cut increment)."""
        return {"u": self.u.x.array.copy(), "r": self.rigid.values.copy(),
                "velocity": self.rigid_velocity.copy(), "acceleration": self.rigid_acceleration.copy(),
                **{name: f.x.array.copy() for name, f in self.history.items()}}

    def restore(self, state: dict) -> None:
        self.u.x.array[:] = state["u"]
        self.rigid.values[:] = state["r"]
        self.rigid.sync()
        self.rigid_velocity[:] = state["velocity"]
        self.rigid_acceleration[:] = state["acceleration"]
        for name, f in self.history.items():
            f.x.array[:] = state[name]
