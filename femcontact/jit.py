"""Several UFL forms compiled as one C module: one C compiler run instead of one per form.

DOLFINx's `fem.form` makes each form its own module. On an empty JIT cache every module costs a
run of the C compiler (about 0.2 s) beside FFCx's code generation; `compile_forms` pays it
once for a problem's forms. The forms it returns are those `fem.form` makes (float64), and the
module lands in the same JIT cache.

FFCx creates a module's C file first, as a lock, and its ready marker (`.c.cached`) after
compiling it; every other process wanting the module waits for the marker for the JIT timeout
(10 s) and then fails. A process killed in between leaves the lock for good, so every later run
of the same forms would fail: `compile_forms` first removes such locks (`clear_stale_locks`).
"""
import time
from pathlib import Path

import ffcx
import ffcx.codegeneration.jit
from dolfinx import cpp, jit
from dolfinx.fem.forms import FormMetaClass

STALE_LOCK_SECONDS = 60.0
"""Age (s) past which a C file without its ready marker is a lock a killed process left: six times
the JIT timeout, which a compiling process must beat for its waiters anyway."""

_Form = type("Form", (FormMetaClass, cpp.fem.Form_float64), {})
_INTEGRAL_TYPES = {"cell": cpp.fem.IntegralType.cell, "exterior_facet": cpp.fem.IntegralType.exterior_facet,
                   "interior_facet": cpp.fem.IntegralType.interior_facet, "vertex": cpp.fem.IntegralType.vertex}


@jit.mpi_jit_decorator
def _compile(forms: list):
    """FFCx and the C compiler on `forms` (rank 0 first; the other ranks then load its module)."""
    return ffcx.codegeneration.jit.compile_forms(forms, parameters=ffcx.get_parameters({"scalar_type": "double"}),
                                                 **jit.get_parameters())


def clear_stale_locks(cache_dir=None, now: float | None = None) -> list[Path]:
    """Remove the JIT cache's C files that have no ready marker and are older than
    `STALE_LOCK_SECONDS` (`cache_dir`: DOLFINx's JIT cache by default); returns those removed."""
    cache_dir = Path(cache_dir or jit.get_parameters()["cache_dir"])
    now = time.time() if now is None else now
    removed = []
    for lock in cache_dir.glob("*.c"):
        try:
            stale = not lock.with_suffix(".c.cached").exists() and now - lock.stat().st_mtime > STALE_LOCK_SECONDS
            if stale:
                lock.unlink()
                removed.append(lock)
        except FileNotFoundError:  # another process finished or cleared it meanwhile
            pass
    return removed


def compile_forms(forms: list) -> list:
    """DOLFINx forms of the UFL `forms` (each on one mesh), compiled together."""
    mesh = forms[0].ufl_domain().ufl_cargo()
    if mesh.comm.rank == 0:
        clear_stale_locks()
    compiled, module, code = _compile(mesh.comm, forms)
    return [_dolfinx_form(form, ufcx_form, module, code) for form, ufcx_form in zip(forms, compiled)]


def _dolfinx_form(form, ufcx_form, module, code):
    """The DOLFINx form of a compiled UFL form: its spaces, coefficients, constants and subdomains."""
    (subdomains,) = form.subdomain_data().values()
    spaces = [argument.ufl_function_space()._cpp_object for argument in form.arguments()]
    coefficients = form.coefficients()
    coefficients = [coefficients[ufcx_form.original_coefficient_position[i]]._cpp_object
                    for i in range(ufcx_form.num_coefficients)]
    constants = [constant._cpp_object for constant in form.constants()]
    markers = {kind: subdomains.get(name) for name, kind in _INTEGRAL_TYPES.items()}
    mesh = form.ufl_domain().ufl_cargo()
    return _Form(ufcx_form, spaces, coefficients, constants, markers, mesh, module.ffi, code)
