"""The plasticity studies on coarse meshes: the plastic strain a pull adds to the wedged thesis
peg and the least damaging pull (`make plasticity_dislodging`), and the support stiffness at
which the insertion's chamfer crossing starts to yield the hole (`make plasticity_insertion`)."""
import pytest

from benchmarks.plasticity_dislodging import plastic_puller
from benchmarks.plasticity_insertion import crossing


@pytest.fixture(scope="module")
def wedged_316():
    """Thesis case 1 wedged on stainless 316 at mesh resolution 0.5 (its mouth corner yields)."""
    return plastic_puller(["mesh.resolution=0.5", "dislodging.tolerance=0.05"])


def test_a_pull_below_the_pullout_adds_plastic_strain_that_grows_with_it(wedged_316):
    """The wedge leaves block A's sharp mouth corner on the yield surface (PEEQ ~5e-3), so a pull
    that does not free the peg still flows there, the more the harder it pulls; the pull-out
    itself adds about 2.2e-4 (resolution 0.5)."""
    peg = wedged_316
    assert peg.wedged_row["max_peeq"] > 1e-3
    weak, strong = (peg.pull(f * peg.pullout_force, "continuous") for f in (0.25, 0.75))
    assert not weak["dislodged"] and not strong["dislodged"]
    assert 0 < weak["peeq_added"] < strong["peeq_added"] < 1e-3
    assert weak["damaging"] == (weak["peeq_added"] > 1e-4) and strong["damaging"] == (strong["peeq_added"] > 1e-4)


def test_the_least_damaging_pull_rises_with_the_strain_limit_and_brackets_it(wedged_316):
    """The bisection of the thresholds finds the least pull adding more than `peeq_limit`:
    its bracket's ends add at most and more than the limit, and a limit half as high again needs
    a harder pull (about 1.5 times: the added strain is nearly proportional to the pull). At 1e-4
    it lies below the pull-out on this mesh (0.46 x): every pull that frees the peg damages it.
    The first bracket, 0.25-0.5 x the pull-out, keeps the search to pulls that hold."""
    peg, found = wedged_316, {}
    peg.settings["bracket"] = [0.25 * peg.pullout_force, 0.5 * peg.pullout_force]
    for limit in (1e-4, 1.5e-4):
        peg.settings["peeq_limit"] = limit
        rows = []
        found[limit] = peg.damage_threshold("continuous", 0.0, rows)
        by_force = {round(row["force_N"], 6): row for row in rows}
        high = found[limit]["damage_threshold_N"]
        low = high - found[limit]["damage_bracket_N"]
        assert by_force[round(high, 6)]["peeq_added"] > limit >= by_force[round(low, 6)]["peeq_added"]
        assert not any(row["dislodged"] for row in rows)
    peg.settings.update(peeq_limit=1e-4, bracket=[])
    assert found[1e-4]["damage_threshold_N"] < 0.6 * peg.pullout_force
    assert found[1.5e-4]["damage_threshold_N"] > 1.3 * found[1e-4]["damage_threshold_N"]


def test_the_chamfer_crossing_yields_only_above_a_support_stiffness():
    """The scene's support (K_x 20 N/mm) crosses the chamfer elastically (peak von Mises well below yield);
    ten times stiffer it presses the chamfer about ten times harder, and the hole yields: PEEQ
    and a plastic zone, the peak stress on the yield surface."""
    soft, stiff = crossing(1, 0.25, increments=15), crossing(10, 0.25, increments=15)  # 0.1 mm
    assert soft["status"] == stiff["status"] == "ok"
    assert soft["peeq_after_chamfer"] == soft["zone_after_chamfer"] == 0 and soft["peak_von_mises"] < 210
    assert stiff["peeq_after_chamfer"] > 0 and stiff["zone_after_chamfer"] > 0
    assert stiff["peak_von_mises"] == pytest.approx(210 + 80 * stiff["peeq_end"], rel=0.02)
    assert 5 * soft["chamfer_peak_Fz"] < stiff["chamfer_peak_Fz"] < 15 * soft["chamfer_peak_Fz"]
