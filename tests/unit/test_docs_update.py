"""`make docs` (benchmarks/docs_update.py) on a temporary repository: fenced blocks take the current
content of the results file (or section) they name, missing results (or sections) are reported with the make
target that writes them, the text outside the markers is left alone, and a bad marker is refused
with one line before any page is written."""
from pathlib import Path

import pytest

from benchmarks.docs_update import main, make_target, update
from femcontact.errors import InputError
from femcontact.families.docs import scene_page

PAGE = """# Bench

Measured by `make bench`:

<!-- generated: results/bench/bench.md#Goals -->
| goal | measured |
|---|---|
| old | 1 |
<!-- end generated -->

Prose kept as it is.

<!-- generated: results/stability/stability.md -->
typed before any run
<!-- end generated -->
"""
BENCH = """# femcontact benchmark

## Goals

| goal | measured |
|---|---|
| Newton per increment | 6 |

### detail of the goals

kept with its section

## Hertz

| L | a |
"""


def repository(tmp_path: Path, page: str = PAGE) -> Path:
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "bench.md").write_text(page)
    (tmp_path / "docs" / "scenes.md").write_text(scene_page())
    (tmp_path / "Makefile").write_text(".PHONY: bench stability\nbench:\n\techo\n")
    (tmp_path / "results" / "bench").mkdir(parents=True)
    (tmp_path / "results" / "bench" / "bench.md").write_text(BENCH)
    return tmp_path


def test_blocks_take_their_results_and_missing_ones_name_their_target(tmp_path, capsys):
    root = repository(tmp_path)
    assert main(["--root", str(root)]) == 0
    text = (root / "docs" / "bench.md").read_text()
    assert text == PAGE.replace("| goal | measured |\n|---|---|\n| old | 1 |\n",
                                "\n| goal | measured |\n|---|---|\n| Newton per increment | 6 |\n\n"
                                "### detail of the goals\n\nkept with its section\n\n")
    printed = capsys.readouterr().out.splitlines()
    assert printed == ["updated docs/bench.md: results/bench/bench.md#Goals",
                       "missing results/stability/stability.md: run `make stability` to write it",
                       "written: docs/bench.md"]
    # a second run finds every block current and writes nothing
    again = update(root)
    assert again.updated == [] and again.written == [] and again.unchanged == [("docs/bench.md", "results/bench/bench.md#Goals")]
    assert (root / "docs" / "bench.md").read_text() == text


def test_a_section_the_results_file_lacks_is_missing_not_an_error(tmp_path):
    """A target run for part of its work writes only that part's sections: the other blocks stay."""
    page = PAGE.replace("#Goals", "#Costs")
    root = repository(tmp_path, page)
    result = update(root)
    assert result.missing == {"results/bench/bench.md#Costs": "make bench",
                              "results/stability/stability.md": "make stability"}
    assert result.written == [] and (root / "docs" / "bench.md").read_text() == page


def test_a_results_file_names_the_target_that_writes_it(tmp_path):
    (tmp_path / "Makefile").write_text(".PHONY: bench bench_hertz_3d\nbench:\n\techo\nbench_hertz_3d:\n\techo\n")
    (tmp_path / "studies").mkdir()
    (tmp_path / "studies" / "wedging.toml").write_text("")
    assert make_target("results/bench/hertz_3d.md", tmp_path) == "make bench_hertz_3d"  # DIR_FILE first
    assert make_target("results/bench/bench.md", tmp_path) == "make bench"
    assert make_target("results/wedging/summary.md", tmp_path) == "make wedging"  # a study's target
    assert make_target("results/rim_3d/rim_3d.md", tmp_path) == "the command its page names"


@pytest.mark.parametrize("page, message", [
    (PAGE.replace("<!-- end generated -->\n\nProse", "\nProse"),
     "docs/bench.md:12: a generated block starts inside the one opened at line 5"),
    (PAGE.rsplit("<!-- end generated -->", 1)[0],
     "docs/bench.md:13: '<!-- generated: results/stability/stability.md -->' is never closed by '<!-- end generated -->'"),
    ("text\n<!-- end generated -->\n", "docs/bench.md:2: '<!-- end generated -->' without a '<!-- generated: ... -->' before it"),
])
def test_a_bad_marker_is_refused_in_one_line_and_nothing_is_written(tmp_path, capsys, page, message):
    root = repository(tmp_path, page)
    (root / "docs" / "other.md").write_text("<!-- generated: results/bench/bench.md#Hertz -->\n<!-- end generated -->\n")
    with pytest.raises(InputError) as error:
        update(root)
    assert str(error.value) == message
    assert main(["--root", str(root)]) == 2
    assert capsys.readouterr().err.strip() == f"error: {error.value}"
    assert (root / "docs" / "bench.md").read_text() == page
    assert (root / "docs" / "other.md").read_text().count("\n") == 2  # the good page is not written either


def test_the_scene_page_is_written_from_the_schemas(tmp_path):
    root = repository(tmp_path)
    (root / "docs" / "scenes.md").write_text("stale\n")
    assert "docs/scenes.md" in update(root).written
    assert (root / "docs" / "scenes.md").read_text() == scene_page()
