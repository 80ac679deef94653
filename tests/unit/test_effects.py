"""Only the effects a scene names are built: inspect the forms, constants and history.

Also checks each law builds what it claims: the stored energy of a uniform stretch
e = 0.1 against Hooke (0.5 (lambda + 2 mu) e^2) and St Venant-Kirchhoff
(0.5 (lambda + 2 mu) (e + e^2/2)^2), plane strain, exact for P1."""
import numpy as np
import pytest
from dolfinx import fem
from mpi4py import MPI

from femcontact.problem.problem import Problem
from femcontact.families import resolve_scene
from geometry.model import build


def problem(effects, **dynamics) -> Problem:
    scene = resolve_scene({"name": "effects", "dim": 2, "geometry": "block", "effects": effects,
                     "block": {"width": 4.0, "height": 2.0}, "indenter": {"shape": "flat", "width": 8.0},
                     "materials": {"block": {"E": 1000.0, "nu": 0.25}}, "dynamics": dynamics,
                     "mesh": {"contact_size": 0.5, "contact_zone": 1.0, "size_max": 1.0},
                     "steps": [{"name": "s"}]})
    return Problem(scene, build(scene, MPI.COMM_WORLD))


def form_constants(p: Problem) -> set:
    names = {id(c): name for name, c in p.constants.items()}
    forms = p.bulk + p.contact_integrand * p.ds_contact
    return {names[id(c)] for c in forms.constants() if id(c) in names}


def history(p: Problem) -> set:
    """History state the effects keep (beyond the unknowns u, r and the last pose)."""
    return set(p.state()) - {"u", "r", "r_old"}


def test_frictionless_quasi_static_builds_no_history_no_mass():
    p = problem(["plane_strain"])
    assert p.built == ["elasticity", "contact", "rigid_corners"]  # the flat punch has sharp corners
    assert history(p) == {"rigid_corners.tangential_old", "rigid_corners.corner_old", "rigid_corners.u_old"}
    assert not p.rigid_residual(None).any() and not p.rigid_stiffness(None).any()
    assert form_constants(p) == {"E", "nu", "gamma"}


def test_friction_adds_anchor_history_and_mu():
    p = problem(["friction", "plane_strain"])
    assert "friction" in p.built and "friction.anchor" in history(p)
    assert {"mu", "gamma_t"} <= form_constants(p)
    assert "density" not in form_constants(p)


def test_inertia_builds_mass_terms_only_when_asked():
    rigid_only = problem(["inertia", "plane_strain"])
    assert {"inertia.velocity", "inertia.acceleration"} == {k for k in history(rigid_only) if k.startswith("inertia")}
    assert "density" not in form_constants(rigid_only)
    full = problem(["inertia", "plane_strain"], deformable_inertia=True)
    assert {"inertia.u_old", "inertia.v_old", "inertia.a_old"} <= history(full)
    assert {"density", "dt", "beta"} <= form_constants(full)


def test_gravity_adds_weight():
    p = problem(["gravity", "plane_strain"])
    assert "gravity" in p.built and {"density", "g"} <= form_constants(p)
    assert p.rigid_residual(None)[1] == pytest.approx(p.rigid.mass * p.scene["dynamics"]["gravity"])


@pytest.mark.parametrize("effects, energy", [
    (["plane_strain"], lambda c, e: 0.5 * c * e * e),
    (["large_strain", "plane_strain"], lambda c, e: 0.5 * c * (e + e * e / 2) ** 2),
])
def test_stored_energy_of_uniform_stretch(effects, energy):
    p = problem(effects)
    e, E, nu = 0.1, 1000.0, 0.25
    lmbda, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    p.u.interpolate(lambda x: np.vstack([e * x[0], 0 * x[1]]))
    value = p.mesh.comm.allreduce(fem.assemble_scalar(fem.form(p.energy_density * p.dx)), op=MPI.SUM)
    assert value / (4.0 * 2.0) == pytest.approx(energy(lmbda + 2 * mu, e), rel=1e-12)


def test_plane_stress_softens_lambda():
    strain, stress = problem(["plane_strain"]), problem(["plane_stress"])
    for p in (strain, stress):
        p.u.interpolate(lambda x: np.vstack([0.01 * x[0], 0 * x[1]]))
    energy = [fem.assemble_scalar(fem.form(p.energy_density * p.dx)) for p in (strain, stress)]
    E, nu = 1000.0, 0.25
    assert energy[1] / energy[0] == pytest.approx((E / (1 - nu * nu)) / (E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))))


def test_compliant_support_is_built_only_when_named():
    """Named: the peg's equations gain the support's springs (a pose error gives -K q at C);
    not named: no support terms at all."""
    from pathlib import Path

    from femcontact.families import load_scene

    path = Path(__file__).resolve().parents[2] / "scenes" / "insertion_2d.toml"
    coarse = ["mesh.contact_size=1.0", "mesh.size_max=3.0", "mesh.contact_zone=1.0", "steps.0.support_motion.y=0.0"]
    for effects, built in ((["friction", "plane_strain", "compliant_support"], True), (["friction", "plane_strain"], False)):
        scene = load_scene(path, coarse + [f"effects={effects}"])
        p = Problem(scene, build(scene, MPI.COMM_WORLD))
        assert ("compliant_support" in p.built) == built
        p.rigid.values[:] = [0.01, 0.0, 0.0]
        assert p.rigid_residual(None)[0] == pytest.approx(scene["support"]["kx"] * 0.01 if built else 0.0)


def test_plasticity_is_built_only_when_named_and_keeps_its_state_at_quadrature_points():
    """Named: built right after elasticity (contact reads its stress), the plastic strain and
    PEEQ become history, the bulk stiffness depends on the state (no factor-once bulk) and the
    rows gain max_peeq and plastic_zone; not named: none of it."""
    elastic, plastic = problem(["plane_strain"]), problem(["plane_strain", "plasticity"])
    assert "plasticity" not in elastic.built and elastic.forms.jacobian_bulk is not None
    assert plastic.built[:3] == ["elasticity", "plasticity", "contact"]
    assert {"plasticity.plastic_strain", "plasticity.PEEQ"} <= history(plastic)
    assert plastic.forms.jacobian_bulk is None
    plastic_effect = plastic.components[1]
    assert plastic_effect.outputs() == {"max_peeq": 0.0, "plastic_zone": 0.0}
    # a uniform shear strain gamma past yield (E = 1000, nu = 0.25: mu = 400, yield 210 MPa at
    # q = sqrt(3) mu gamma, perfectly plastic): the whole block flows, PEEQ = (gamma - gamma_y)/sqrt(3)
    gamma = 1.0
    plastic.u.interpolate(lambda x: np.vstack([gamma * x[1], 0 * x[0]]))
    gamma_y = 210.0 / (np.sqrt(3) * 400.0)
    out = plastic_effect.outputs()
    assert out["max_peeq"] == pytest.approx((gamma - gamma_y) / np.sqrt(3), rel=1e-12)
    assert out["plastic_zone"] == pytest.approx(4.0 * 2.0, rel=1e-12)
    before = plastic.state()
    plastic_effect.commit(0.0)
    assert plastic.components[1].quadrature.peeq.x.array.max() > 0
    plastic.restore(before)
    assert plastic.components[1].quadrature.peeq.x.array.max() == 0.0


def test_the_solver_gets_its_physical_scales_from_the_effects():
    """What Newton needs of the physics (its regularisation, stabilisation and round-off floor), in
    the scene's numbers: E = 1000 MPa, gamma = 10 (default), h_contact = 0.5 mm, the flat punch's
    largest dimension 8 mm; with inertia the problem has a time-stepping effect."""
    p = problem(["plane_strain"])
    assert p.stiffness_scale() == 1000.0
    assert p.contact_size == pytest.approx(0.5)
    assert p.contact_stiffness() == pytest.approx(10.0 * 1000.0 / p.contact_size, rel=1e-15)
    assert p.body_size == max(p.model.rigid["half_width"], p.model.rigid["length"]) == 8.0
    p.constants["E"].value = 2000.0  # a sweep's new value is seen without rebuilding
    assert p.stiffness_scale() == 2000.0 and p.contact_stiffness() == pytest.approx(20000.0 / p.contact_size)
    assert p.time_stepping is None and problem(["plane_strain", "inertia"]).time_stepping is not None
