"""A study's report films the cases [animation] selects: they run with their time series, and
index.html plays the MP4 (summary.md shows the GIF)."""
import json
from pathlib import Path

from femcontact.cli import main
from femcontact.study.study_file import load_study

ROOT = Path(__file__).resolve().parents[2]


def test_report_embeds_the_selected_cases_animation(tmp_path, capsys):
    study = tmp_path / "film.toml"
    study.write_text(f'[study]\nname = "film"\nscene = "{ROOT / "scenes" / "wedging_2d.toml"}"\njobs = 2\n'
                     '[scene]\n"mesh.resolution" = 0.5\n"steps.0.increments" = 2\n"steps.1.increments" = 2\n'
                     '[sweep]\ncases = [ { "peg.insertion_depth" = 5.0 }, { "peg.insertion_depth" = 6.0 } ]\n'
                     '[animation]\nselect = [ { "peg.insertion_depth" = 6.0 } ]\n')
    cases = {case.params["peg.insertion_depth"]: case for case in load_study(study, results_root=tmp_path).cases}
    assert cases[6.0].scene["outputs"]["fields"] and not cases[5.0].scene["outputs"]["fields"]
    assert main(["study", str(study), "--results", str(tmp_path), "--quiet"]) == 0
    assert main(["report", str(study), "--results", str(tmp_path)]) == 0
    films = tmp_path / "film" / "animations"
    assert sorted(p.name for p in films.iterdir()) == [f"{cases[6.0].id}.gif", f"{cases[6.0].id}.mp4"]
    page = (tmp_path / "film" / "index.html").read_text()
    assert f'<video src="animations/{cases[6.0].id}.mp4"' in page
    assert f"(animations/{cases[6.0].id}.gif)" in (tmp_path / "film" / "summary.md").read_text()
    assert json.loads((cases[6.0].dir / "result.json").read_text())["status"] == "ok"
