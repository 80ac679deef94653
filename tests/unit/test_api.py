"""The Python API (femcontact/api.py): docs/api.md's examples run as written, the command line and
the API give the same case, `import femcontact` stays light."""
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def python(code: str, cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=900)


def workspace(tmp_path: Path) -> Path:
    """A directory with the repository's scenes and studies, so results/ is written there."""
    for name in ("scenes", "studies"):
        (tmp_path / name).symlink_to(ROOT / name)
    return tmp_path


def code_blocks(page: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", page.read_text(), flags=re.S)


def test_import_femcontact_loads_no_finite_element_library():
    result = python("import sys, femcontact; femcontact.InputError; "
                    "print(sorted(m for m in ('dolfinx', 'mpi4py', 'petsc4py', 'ufl', 'gmsh', 'numpy') "
                    "if m in sys.modules))", ROOT)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["[]"]


@pytest.mark.parametrize("index", range(len(code_blocks(ROOT / "docs" / "api.md"))))
def test_docs_api_examples_run(tmp_path, index):
    block = code_blocks(ROOT / "docs" / "api.md")[index]
    result = python(block, workspace(tmp_path))
    assert result.returncode == 0, f"docs/api.md example {index + 1} failed:\n{block}\n{result.stderr[-3000:]}"


def test_api_and_command_line_write_the_same_case(tmp_path):
    """`femcontact run` is load_scene + run: the same metrics; Result.history is history.csv."""
    import femcontact

    scene = femcontact.load_scene(ROOT / "scenes" / "wedging_2d.toml", ["mesh.resolution=0.5"])
    assert scene == femcontact.load_scene(ROOT / "scenes" / "wedging_2d.toml", {"mesh.resolution": 0.5})
    command = python(f"from femcontact.cli import main; raise SystemExit(main(['run', 'scenes/wedging_2d.toml', "
                     f"'--set', 'mesh.resolution=0.5', '--out', {str(tmp_path / 'cli')!r}, '--quiet']))", ROOT)
    assert command.returncode == 0, command.stderr
    result = femcontact.run(scene, out=tmp_path / "api", quiet=True)
    written = json.loads((tmp_path / "cli" / "result.json").read_text())
    assert result.status == written["status"] == "ok"
    assert result.metrics["wedged"] == written["metrics"]["wedged"]
    assert result.metrics["residual_force_A"] == pytest.approx(written["metrics"]["residual_force_A"], rel=1e-9)
    assert femcontact.Result.read(tmp_path / "api").metrics == json.loads(json.dumps(result.metrics))
    history = result.history
    header = (tmp_path / "api" / "history.csv").read_text().splitlines()[0].split(",")
    assert list(history) == header
    assert len(history["time"]) == result.metrics["increments"] == 10
    assert np.asarray(history["time"])[-1] == pytest.approx(result.metrics["release.time"])
    assert np.asarray(history["tilt_deg"])[-1] == pytest.approx(result.metrics["release.tilt_deg"])
    assert set(result.fields) == {"npz"}


def test_api_errors_are_the_command_lines(tmp_path):
    import femcontact

    with pytest.raises(femcontact.InputError, match=r"peg\.width = -1\.0: out of range"):
        femcontact.load_scene(ROOT / "scenes" / "wedging_2d.toml", {"peg.width": -1.0})
    with pytest.raises(femcontact.InputError, match=r"hole\.nosuchkey: unknown key"):
        femcontact.Study(ROOT / "studies" / "wedging.toml", {"hole.nosuchkey": 1.0}, results_root=tmp_path)
