"""The layering rules of docs/architecture.md, checked on the source text.

- geometry/ is the lowest layer: it imports nothing from femcontact;
- the measurement programs (benchmarks/) import the library, never the other way;
- no import cycles between modules (module-level and function-level imports alike);
- the solver names no effect: effects reach it only through the problem's hooks;
- the solver names no material constant and no body, and reads no scene key: the scene reaches it
  translated (`femcontact.problem`: unknowns, forms, load steps), its settings as `SolverOptions`;
- only the packages that assemble PETSc objects import petsc4py;
- each effect module defines one Effect class, and docs/scenes.md is the generated page.
"""
import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
EFFECT_WORDS = {"friction", "inertia", "gravity", "anchor", "corners", "rigid_corners", "stick", "slip", "newmark"}


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def sources() -> dict[str, Path]:
    return {module_name(p): p for package in ("femcontact", "geometry", "benchmarks")
            for p in (ROOT / package).rglob("*.py")}


def imports(path: Path, modules: set[str]) -> set[str]:
    """Project modules imported anywhere in the file (a `from package import module` counts as the module)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module:
            names = [f"{node.module}.{alias.name}" for alias in node.names] + [node.module]
        else:
            continue
        for name in names:
            while name and name not in modules:
                name = name.rpartition(".")[0]
            if name:
                found.add(name)
    return found


def graph() -> dict[str, set[str]]:
    modules = sources()
    names = set(modules)
    # a package's __init__ is imported on the way to its modules; it is not a dependency edge
    return {name: {m for m in imports(path, names) if m != name and not name.startswith(m + ".")}
            for name, path in modules.items()}


def test_geometry_imports_nothing_from_femcontact():
    offenders = {name: sorted(m for m in deps if m.startswith("femcontact"))
                 for name, deps in graph().items() if name.startswith("geometry")}
    assert {k: v for k, v in offenders.items() if v} == {}


def test_the_library_never_imports_a_measurement_program():
    """Not by an import (at module level or inside a function) nor by a "benchmarks.MODULE" string
    that a worker or `importlib` would import."""
    offenders = {name: sorted(m for m in deps if m.startswith("benchmarks"))
                 for name, deps in graph().items() if not name.startswith("benchmarks")}
    named = {name: sorted(word for word in string_constants(path) if word.startswith("benchmarks."))
             for name, path in sources().items() if not name.startswith("benchmarks")}
    assert {k: v for k, v in {**offenders, **named}.items() if v} == {}


def string_constants(path: Path) -> set[str]:
    """The string constants of a module."""
    return {node.value for node in ast.walk(ast.parse(path.read_text()))
            if isinstance(node, ast.Constant) and isinstance(node.value, str)}


def test_no_import_cycles():
    edges, state, cycles = graph(), {}, []

    def visit(node, stack):
        state[node] = "open"
        for nxt in sorted(edges.get(node, ())):
            if state.get(nxt) == "open":
                cycles.append(stack[stack.index(nxt):] + [nxt] if nxt in stack else [node, nxt])
            elif nxt not in state:
                visit(nxt, stack + [nxt])
        state[node] = "done"

    for node in sorted(edges):
        if node not in state:
            visit(node, [node])
    assert cycles == []


def identifiers(path: Path) -> set[str]:
    """Names, attributes and string constants of a module, docstrings and comments excluded."""
    tree = ast.parse(path.read_text())
    docstrings = {id(node.body[0].value) for node in ast.walk(tree)
                  if isinstance(node, (ast.Module, ast.FunctionDef, ast.ClassDef)) and node.body
                  and isinstance(node.body[0], ast.Expr) and isinstance(node.body[0].value, ast.Constant)}
    words = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name):
            words.add(node.id)
        elif isinstance(node, ast.Attribute):
            words.add(node.attr)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings:
            words.add(node.value)
    return {w.lower() for word in words for w in word.replace(".", "_").split("_")} | {w.lower() for w in words}


def test_solver_names_no_effect():
    for path in (ROOT / "femcontact" / "solver").glob("*.py"):
        assert identifiers(path) & EFFECT_WORDS == set(), path.name


MATERIAL_CONSTANTS = {"E", "nu", "gamma", "gamma_t", "mu", "theta", "density", "yield_stress", "materials"}
BODIES = {"peg", "hole", "indenter", "spring", "block"}
PETSC_USERS = ("femcontact.solver", "femcontact.effects", "femcontact.outputs")
"""Packages that assemble PETSc vectors and matrices (contact vectors, recorded reactions)."""


def strings(path: Path) -> set[str]:
    """String constants of a module, docstrings excluded."""
    tree = ast.parse(path.read_text())
    docstrings = {id(node.body[0].value) for node in ast.walk(tree)
                  if isinstance(node, (ast.Module, ast.FunctionDef, ast.ClassDef)) and node.body
                  and isinstance(node.body[0], ast.Expr) and isinstance(node.body[0].value, ast.Constant)}
    return {node.value for node in ast.walk(tree)
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings}


def scene_reads(path: Path) -> list[str]:
    """Subscripts of a scene (`scene[...]`, `self.scene[...]`) and of a "solver" key, as source text."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if not isinstance(node, ast.Subscript):
            continue
        value = node.value
        name = value.id if isinstance(value, ast.Name) else value.attr if isinstance(value, ast.Attribute) else ""
        key = node.slice.value if isinstance(node.slice, ast.Constant) else None
        if name == "scene" or key == "solver":
            found.append(ast.unparse(node))
    return found


def test_solver_names_no_material_constant_no_body_and_reads_no_scene_key():
    for path in (ROOT / "femcontact" / "solver").glob("*.py"):
        words = {w for text in strings(path) for w in text.replace(".", " ").split()}
        assert strings(path) & MATERIAL_CONSTANTS == set(), path.name
        assert words & BODIES == set(), path.name
        assert scene_reads(path) == [], path.name


def test_only_the_packages_that_assemble_petsc_objects_import_petsc4py():
    importers = set()
    for name, path in sources().items():
        for node in ast.walk(ast.parse(path.read_text())):
            modules = ([alias.name for alias in node.names] if isinstance(node, ast.Import)
                       else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            if any(module.split(".")[0] == "petsc4py" for module in modules):
                importers.add(name)
    assert importers and {name for name in importers if not name.startswith(PETSC_USERS)} == set()


def test_each_effect_is_one_module_with_one_effect_class():
    from femcontact import effects
    from femcontact.effects.base import Effect

    named = {**effects.MATERIAL, **effects.NAMED}
    classes = list(effects.ALWAYS) + list(named.values()) + list(effects.BY_SHAPE)
    assert all(issubclass(cls, Effect) for cls in classes)
    assert len({cls.__module__ for cls in classes}) == len(classes)
    assert {cls.name for cls in named.values()} == set(named)
    for path in (ROOT / "femcontact" / "effects").glob("*.py"):
        if path.stem in ("__init__", "base"):
            continue
        tree = ast.parse(path.read_text())
        bases = [node for node in tree.body if isinstance(node, ast.ClassDef)
                 and any(getattr(b, "id", "") == "Effect" for b in node.bases)]
        assert len(bases) == 1, path.name


def test_named_effects_are_the_scene_effects_that_build_terms():
    from femcontact import effects
    from femcontact.config.scene import EFFECTS

    law_choices = {"large_strain", "plane_strain", "plane_stress"}  # select the elastic law (effects/elasticity.py)
    assert set(EFFECTS) == set(effects.MATERIAL) | set(effects.NAMED) | law_choices


def test_scene_page_is_generated_from_the_schema():
    from femcontact.families.docs import scene_page

    assert (ROOT / "docs" / "scenes.md").read_text() == scene_page()
