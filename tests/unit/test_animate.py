"""`femcontact animate`: a playable MP4 (and a GIF) with one picture per frame of the time series."""
import json
import subprocess
from pathlib import Path

import pytest
from PIL import Image

from femcontact.cli import main
from femcontact.families import load_scene
from femcontact.families.case import run_contact

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    """The wedging scene on a coarse mesh, 3 + 3 increments, every frame written."""
    out = tmp_path_factory.mktemp("wedging")
    scene = load_scene(ROOT / "scenes" / "wedging_2d.toml", {"mesh.resolution": 0.5, "outputs.fields": True,
                                                              "steps.0.increments": 3, "steps.1.increments": 3})
    run_contact(scene, out)
    return out


def probe(path: Path) -> dict:
    """Frames decoded, width and height of a video's first stream (ffprobe)."""
    result = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
                             "stream=nb_read_frames,width,height,codec_name", "-of", "json", str(path)],
                            capture_output=True, text=True, check=True)
    return json.loads(result.stdout)["streams"][0]


def test_animation_has_a_frame_per_increment(case, capsys):
    assert main(["animate", str(case), "--fps", "5"]) == 0
    assert "animation.mp4" in capsys.readouterr().out
    video = probe(case / "animation.mp4")
    assert video["codec_name"] == "h264" and int(video["nb_read_frames"]) == 6
    assert (video["width"], video["height"]) == (1280, 560)
    with Image.open(case / "animation.gif") as gif:
        assert gif.n_frames == 6 and gif.size == (1280, 560)


def test_animate_without_fields_names_the_missing_file(tmp_path, capsys):
    assert main(["animate", str(tmp_path)]) == 2
    assert "fields.xdmf: missing; run the scene with --set outputs.fields=true" in capsys.readouterr().err


def test_animate_refuses_an_unknown_force_column(case, capsys):
    assert main(["animate", str(case), "--force", "contact_C_force"]) == 2
    assert "--force contact_C_force: not a column of history.csv" in capsys.readouterr().err
