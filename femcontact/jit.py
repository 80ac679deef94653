"""Several UFL forms compiled as one C module: one C compiler run instead of one per form.

DOLFINx's `fem.form` makes each form its own module. On an empty JIT cache every module costs a
run of the C compiler (about 0.2 s) beside FFCx's code generation; `compile_forms` pays it
once for a problem's forms. The forms it returns are those `fem.form` makes (float64), and the
module lands in the same JIT cache.
"""
import ffcx
import ffcx.codegeneration.jit
from dolfinx import cpp, jit
from dolfinx.fem.forms import FormMetaClass

_Form = type("Form", (FormMetaClass, cpp.fem.Form_float64), {})
_INTEGRAL_TYPES = {"cell": cpp.fem.IntegralType.cell, "exterior_facet": cpp.fem.IntegralType.exterior_facet,
                   "interior_facet": cpp.fem.IntegralType.interior_facet, "vertex": cpp.fem.IntegralType.vertex}


@jit.mpi_jit_decorator
def _compile(forms: list):
    """FFCx and the C compiler on `forms` (rank 0 first; the other ranks then load its module)."""
    return ffcx.codegeneration.jit.compile_forms(forms, parameters=ffcx.get_parameters({"scalar_type": "double"}),
                                                 **jit.get_parameters())


def compile_forms(forms: list) -> list:
    """DOLFINx forms of the UFL `forms` (each on one mesh), compiled together."""
    mesh = forms[0].ufl_domain().ufl_cargo()
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
