"""Forms compiled together (`femcontact.jit.compile_forms`) are DOLFINx's own forms, from one module."""
import ffcx.codegeneration.jit
import numpy as np
import pytest
import ufl
from dolfinx import fem, mesh
from dolfinx.fem import petsc
from mpi4py import MPI

from femcontact.jit import compile_forms


@pytest.fixture(scope="module")
def forms():
    """A functional, a vector and a matrix form with a coefficient, a constant and a facet subdomain."""
    domain = mesh.create_unit_square(MPI.COMM_WORLD, 4, 3)
    V = fem.VectorFunctionSpace(domain, ("Lagrange", 2))
    u, v, du = fem.Function(V), ufl.TestFunction(V), ufl.TrialFunction(V)
    u.interpolate(lambda x: np.vstack([x[0] ** 2 + x[1], np.sin(x[0]) * x[1]]))
    c = fem.Constant(domain, 3.0)
    facets = mesh.locate_entities_boundary(domain, 1, lambda x: np.isclose(x[0], 1.0))
    tags = mesh.meshtags(domain, 1, facets, np.full(len(facets), 7, dtype=np.int32))
    ds = ufl.Measure("ds", domain=domain, subdomain_data=tags)
    residual = c * ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx + ufl.dot(u, u) * v[0] * ds(7)
    return [c * ufl.dot(u, u) * ufl.dx + u[1] * ds(7), residual, ufl.derivative(residual, u, du)]


def values(form) -> np.ndarray:
    """A compiled form assembled: a number, a vector or a matrix's entries (this rank's rows)."""
    rank = len(form.function_spaces)
    if rank == 0:
        return np.array([form.mesh.comm.allreduce(fem.assemble_scalar(form), op=MPI.SUM)])
    if rank == 1:
        vector = petsc.assemble_vector(form)
        return vector.array.copy()
    matrix = petsc.assemble_matrix(form)
    matrix.assemble()
    return matrix.getValuesCSR()[2].copy()


def test_forms_compiled_together_assemble_as_dolfinx_compiles_them(forms):
    together = compile_forms(forms)
    for alone, joint in zip(forms, together):
        expected = values(fem.form(alone))
        assert np.abs(values(joint) - expected).max() <= 1e-13 * np.abs(expected).max()
        assert np.abs(expected).max() > 0


def test_forms_compiled_together_come_from_one_module(forms, monkeypatch):
    calls = []
    compile_with_ffcx = ffcx.codegeneration.jit.compile_forms

    def counted(ufl_forms, **kwargs):
        calls.append(len(ufl_forms))
        return compile_with_ffcx(ufl_forms, **kwargs)

    monkeypatch.setattr(ffcx.codegeneration.jit, "compile_forms", counted)
    compile_forms(forms)
    assert calls == [len(forms)]  # one FFCx module for all of them (on every rank)


def test_a_lock_left_by_a_killed_compile_is_cleared(tmp_path):
    """A C file without its ready marker older than STALE_LOCK_SECONDS is a killed process's lock
    and goes; one with its marker, or one still young (a compile under way), stays."""
    import os
    import time

    from femcontact.jit import STALE_LOCK_SECONDS, clear_stale_locks

    now = time.time()
    old = now - 2 * STALE_LOCK_SECONDS
    killed, compiled, young = (tmp_path / f"libffcx_forms_{name}.c" for name in ("killed", "compiled", "young"))
    for path in (killed, compiled, young):
        path.write_text("")
    (tmp_path / "libffcx_forms_compiled.c.cached").write_text("")
    for path in (killed, compiled):
        os.utime(path, (old, old))
    assert clear_stale_locks(tmp_path, now) == [killed]
    assert not killed.exists() and compiled.exists() and young.exists()
