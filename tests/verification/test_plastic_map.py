"""The wedge map with plasticity (`make plasticity_wedging`) on a coarse mesh: two map points run
elastic and on stainless 316 through the case runner, paired by the family's gathering."""
from pathlib import Path

import pytest

import femcontact
from femcontact.families.wedging import plastic_map
from femcontact.study.gathering import ok_cases
from femcontact.study.study_file import load_study

ROOT = Path(__file__).resolve().parents[2]
LAWS = {plastic_map.ELASTIC: "",
        plastic_map.PLASTIC: 'effects = ["friction", "plane_strain", "plasticity"]\n'
                             '"plasticity.hardening" = [[0.0, 210.0], [1.0, 290.0]]\n'}
POINTS = '[sweep]\ncases = [{ "steps.0.force" = [-1.0, 0.2] }, { "steps.0.force" = [-25.0, 5.0] }]\n'


@pytest.fixture(scope="module")
def gathered(tmp_path_factory):
    """l_d 5 at mesh resolution 0.5, pushed by a fifth of the thesis' push and by five times it,
    then released, each case run as a study runs it; the gathering's rows and its directory."""
    folder = tmp_path_factory.mktemp("map")
    cases = {}
    for name, law in LAWS.items():
        study_file = folder / f"{name}.toml"
        study_file.write_text(f'[study]\nname = "{name}"\nscene = "{ROOT / "scenes" / "wedging_2d.toml"}"\n'
                              f'[scene]\n"mesh.resolution" = 0.5\n{law}{POINTS}')
        for case in load_study(study_file, results_root=folder).cases:
            femcontact.run(case.scene, out=case.dir, quiet=True)
        cases[name] = ok_cases(study_file, folder)
    plastic_map.write(cases, folder)
    return plastic_map.pair(cases)[0], folder, cases


def test_below_yield_the_plastic_run_is_the_elastic_one(gathered):
    """The light push stays far below yield: no plastic strain anywhere (exactly 0) and the residual
    force that holds the peg is the elastic one to the solver's tolerance."""
    light = next(r for r in gathered[0] if r["load"] == "F (-1, 0.2) N")
    assert light["elastic_over_yield"] < 0.5
    assert light["max_peeq"] == 0.0 and light["plastic_zone"] == 0.0 and not light["yielded_plastic"]
    assert light["wedged_elastic"] and light["wedged_plastic"]
    assert abs(light["R_A_change"]) < 1e-6


def test_above_yield_the_corners_flow_and_the_stress_stays_on_the_hardening_curve(gathered):
    """Five times the push loads the elastic blocks past yield; the plastic run flows (PEEQ > 0 in
    a zone of positive area) and its peak von Mises stress lies between the initial yield stress
    and the yield stress at its peak PEEQ (210 + 80 PEEQ MPa, the 316 line), far below the elastic
    peak."""
    heavy = next(r for r in gathered[0] if r["load"] == "F (-25, 5) N")
    assert heavy["elastic_over_yield"] > 1.5
    assert heavy["yielded_plastic"] and heavy["max_peeq"] > 0 and heavy["plastic_zone"] > 0
    assert 210.0 <= heavy["peak_von_mises_plastic_MPa"] <= (210.0 + 80.0 * heavy["max_peeq"]) * (1 + 1e-9)
    assert heavy["R_A_change"] is not None and heavy["wedged_elastic"]


def test_the_gathering_writes_its_page_table_and_plot(gathered):
    rows, results, _ = gathered
    page = (results / "plasticity_wedging.md").read_text()
    assert "| 5 | 40.1 | 0.2 | F (-25, 5) N | 1.77 | 0.62 | yes / yes |" in page
    assert "passes the yield stress at 1, the plastic run yields (PEEQ > 0) at 1 (the same points)" in page
    assert len((results / "plasticity_wedging.csv").read_text().splitlines()) == 1 + len(rows) == 3
    assert (results / "plasticity_wedging.png").stat().st_size > 10_000


def test_a_point_run_only_one_way_is_listed_not_paired(gathered):
    """A point whose plastic run is missing (failed, or not run yet) is named under the table."""
    cases = gathered[2]
    rows, alone = plastic_map.pair({**cases, plastic_map.PLASTIC: cases[plastic_map.PLASTIC][1:]})
    assert len(rows) == 1 and [scene["steps"][0]["force"] for scene in alone] == [[-1.0, 0.2]]
    assert "1 map point(s) with only one of the two results" in plastic_map.page(rows, alone)
