"""The package table of docs/architecture.md is the import rule, and the code follows it.

Each row of the table names packages (`name/`, every module below it) or modules (`name.py`) and
their layer; a module may import from its own layer and the layers below, never above. Every
import counts, those inside functions too. Every module of the product has a row, and every row
names something that exists.
"""
import re

from tests.unit.test_architecture import ROOT, graph, sources

ROW = re.compile(r"^\|\s*(\d+)\s*\|\s*((?:`[^`]+`,?\s*)+)\|")


def layers() -> tuple[dict[str, int], dict[str, int]]:
    """({package: layer}, {module: layer}) from the table's rows, as dotted names."""
    packages, modules = {}, {}
    for line in (ROOT / "docs" / "architecture.md").read_text().splitlines():
        match = ROW.match(line)
        for name in re.findall(r"`([^`]+)`", match.group(2)) if match else []:
            if name.endswith("/"):
                packages[name.strip("/").replace("/", ".")] = int(match.group(1))
            else:
                modules[name.removesuffix(".py").replace("/", ".").removesuffix(".__init__")] = int(match.group(1))
    return packages, modules


def layer_of(module: str, table) -> int | None:
    """The layer of a module: its own row, else its innermost package's row."""
    packages, modules = table
    if module in modules:
        return modules[module]
    while module and module not in packages:
        module = module.rpartition(".")[0]
    return packages.get(module)


def test_every_module_has_a_row_and_every_row_exists():
    table, found = layers(), sources()
    assert sorted(m for m in found if layer_of(m, table) is None) == []
    packages, modules = table
    assert sorted(name for name in packages if not any(m == name or m.startswith(name + ".") for m in found)) == []
    assert sorted(name for name in modules if name not in found) == []


def test_imports_go_down_the_layers():
    table = layers()
    upward = sorted(f"{module} (layer {layer_of(module, table)}) imports {dep} (layer {layer_of(dep, table)})"
                    for module, deps in graph().items() for dep in deps
                    if layer_of(dep, table) > layer_of(module, table))
    assert upward == []
