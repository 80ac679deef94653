"""The family registry: a family written as one object and registered by one line is found by scene
resolution, the case runner, the study report and `make accuracy`; nothing outside
femcontact/families names a family."""
import ast
import json
import re
from pathlib import Path

import pytest

from femcontact import families
from femcontact.config.schema import Field, validate
from femcontact.errors import InputError
from femcontact.families import case
from femcontact.families.family import Family
from femcontact.study import report

ROOT = Path(__file__).resolve().parents[2]

TOY_SCHEMA = {
    "kind": Field("str", "spring", choices=("spring",)),
    "name": Field("str", "spring", "scene name"),
    "spring": {"k": Field("float", 200.0, "stiffness (N/mm)", positive=True),
               "force": Field("float", 10.0, "applied force (N)")},
}


def toy_run(scene: dict, case_dir, checkpoint: bool = False, restart=None) -> dict:
    """A linear spring under a force: its extension F / k (mm) and stored energy F^2 / (2 k) (N*mm)."""
    k, force = scene["spring"]["k"], scene["spring"]["force"]
    return {"metrics": {"extension": force / k, "energy": force * force / (2 * k)}, "timings": {}, "info": {}}


def toy_plot(spec: dict, rows: list[dict], results: Path, column) -> Path:
    """A plot kind that writes the extensions it is given, one per line."""
    path = results / (spec["file"] or "extensions.txt")
    path.write_text("".join(f"{column(row, 'extension')}\n" for row in rows))
    return path


TOY = Family(name="spring", kinds=("spring",), resolve=lambda data: validate(data, TOY_SCHEMA), run_case=toy_run,
             primary_columns=("extension", "energy"), plots={"extensions": toy_plot})


@pytest.fixture
def registered(monkeypatch):
    """The toy family registered: the one line a new family adds to FAMILIES."""
    monkeypatch.setattr(families, "FAMILIES", [*families.FAMILIES, TOY])


def test_a_registered_family_is_resolved_run_and_reported(registered, tmp_path):
    scene = families.resolve_scene({"kind": "spring"}, ["spring.k=50.0"])
    assert scene == {"kind": "spring", "name": "spring", "spring": {"k": 50.0, "force": 10.0}}
    with pytest.raises(InputError, match="spring.k"):
        families.resolve_scene({"kind": "spring", "spring": {"k": -1.0}})
    assert families.family_of(scene) is TOY
    metrics = case.run_case(scene, tmp_path)["metrics"]
    assert metrics == {"extension": pytest.approx(0.2), "energy": pytest.approx(1.0)}  # F/k, F^2/(2k)
    rows = [{"case_id": "a", "status": "ok", "scene": scene, "extension": metrics["extension"]}]
    spec = {"kind": "extensions", "file": "", "x": "spring.k", "y": "extension"}
    path = report.write_plot(spec, rows, tmp_path, ["spring.k"])
    assert path.read_text() == "0.2\n"
    assert families.primary_columns(["energy", "extension", "spring.k"]) == ["extension", "energy"]


def test_an_unregistered_kind_is_refused_naming_the_kinds():
    with pytest.raises(InputError, match=r"kind = 'spring': not allowed, expected one of 'contact', .*'rcc'"):
        families.resolve_scene({"kind": "spring"})


def test_every_family_declares_its_kinds_claims_and_accuracy_rows():
    kinds = [kind for family in families.FAMILIES for kind in family.kinds]
    assert len(kinds) == len(set(kinds)) and "contact" not in kinds
    for family in families.FAMILIES:
        assert bool(family.kinds) == bool(family.resolve) and not (family.kinds and family.claims)
        assert (ROOT / family.doc).exists(), family.doc
    from benchmarks.accuracy import PROBLEMS

    assert all(PROBLEMS[family.name] is family.accuracy for family in families.FAMILIES if family.accuracy)


def test_contact_scenes_go_to_the_family_that_claims_them():
    scenes = {"wedging": ("peg_in_hole", []), "insertion": ("peg_in_hole", ["compliant_support"]),
              "snap_fit": ("snap_fit", []), "hertz": ("block", [])}
    for name, (geometry, effects) in scenes.items():
        scene = {"kind": "contact", "geometry": geometry, "effects": effects}
        assert families.family_of(scene).name == name


def test_no_kind_is_named_outside_the_families_package():
    """Dispatch on a scene's kind happens through the registry only."""
    kinds = sorted(kind for family in families.FAMILIES for kind in family.kinds)
    pattern = re.compile(r"""(==|!=|\bin)\s*\(?["'](%s)["']""" % "|".join(map(re.escape, kinds)))
    found = [f"{path.relative_to(ROOT)}:{number}: {line.strip()}"
             for path in sorted((ROOT / "femcontact").rglob("*.py")) if "families" not in path.parts
             for number, line in enumerate(path.read_text().splitlines(), 1) if pattern.search(line)]
    assert found == []


def _code_words(path: Path) -> set[str]:
    """The identifiers and the words of the strings of a module's code (docstrings and comments,
    which may explain generically, left out)."""
    tree = ast.parse(path.read_text())
    docstrings = {id(node.body[0].value) for node in ast.walk(tree)
                  if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
                  and node.body and isinstance(node.body[0], ast.Expr) and isinstance(node.body[0].value, ast.Constant)}
    words = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings:
            words |= set(re.findall(r"\w+", node.value))
        elif isinstance(node, ast.Name):
            words.add(node.id)
        elif isinstance(node, ast.Attribute):
            words.add(node.attr)
        elif isinstance(node, ast.alias):
            words |= set(re.findall(r"\w+", node.name))
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            words.add(node.name)
        elif isinstance(node, ast.arg):
            words.add(node.arg)
    return words


def test_the_study_package_names_no_family():
    """The study runner and report reach a family's knowledge (e.g. the scene tables a shared prefix
    leaves out) through the registry only."""
    names = {family.name for family in families.FAMILIES} | {k for family in families.FAMILIES for k in family.kinds}
    found = {f"{path.relative_to(ROOT)}: {word}" for path in sorted((ROOT / "femcontact" / "study").rglob("*.py"))
             for word in _code_words(path) & names}
    assert sorted(found) == []


def test_a_gathering_gets_the_ok_cases_its_study_files_make_now(monkeypatch, tmp_path):
    """A report across studies sees the cases each study file makes, those that ended ok, and no
    stale case directory of an earlier sweep."""
    from femcontact.study import gathering
    from femcontact.study.study_file import load_study

    (tmp_path / "spring.toml").write_text('kind = "spring"\n')
    study_file = tmp_path / "springs.toml"
    study_file.write_text('[study]\nname = "springs"\nscene = "spring.toml"\n'
                          '[sweep]\ngrid = { "spring.k" = [50.0, 100.0, 200.0] }\n')
    handed = {}
    springs_all = families.Gathering("springs_all", (study_file,), lambda cases, out: handed.update(cases))
    toy = Family(name="spring", kinds=("spring",), resolve=TOY.resolve, gatherings=(springs_all,))
    monkeypatch.setattr(families, "FAMILIES", [*families.FAMILIES, toy])
    results = tmp_path / "results"
    cases = load_study(study_file, results_root=results).cases
    for made, status in zip(cases, ("ok", "failed", "ok")):
        made.dir.mkdir(parents=True)
        result = {"status": status, "metrics": {"k": made.scene["spring"]["k"]}}
        (made.dir / "result.json").write_text(json.dumps(result))
    stale = results / "springs" / "cases" / "000000000000"
    stale.mkdir()
    (stale / "result.json").write_text('{"status": "ok", "metrics": {"k": 1.0}}')
    assert gathering.main(["springs_all", "--results", str(results)]) == 0
    assert [(made.id, metrics) for made, metrics in handed["springs"]] == [(cases[0].id, {"k": 50.0}),
                                                                           (cases[2].id, {"k": 200.0})]
    assert (results / "springs_all").is_dir()
