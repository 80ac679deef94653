"""Reports lead with the answer: result columns first, inputs after; the dislodging summary's
thresholds table from the cases' metrics and pulls."""
import csv
import json
from types import SimpleNamespace

import pytest

from femcontact.families.dislodging import report as dislodging
from femcontact.study.report import answer_first


def test_results_then_inputs_then_the_run():
    rows = [{"scene": {"peg": {"width": 40.0}, "contact": {"mu": 0.2}}, "case_id": "a", "status": "ok",
             "peg.insertion_depth": 5.0, "wedged": 1, "l_crit": 2.8, "wall": 1.0}]
    columns = ["case_id", "peg.insertion_depth", "peg.width", "status", "l_crit", "wedged", "wall", "time.total"]
    assert answer_first(columns, ["peg.insertion_depth"], rows) == \
        ["l_crit", "wedged", "peg.insertion_depth", "peg.width", "case_id", "status", "wall", "time.total"]


def case(tmp_path, number: int, method: str, hz: float, threshold: float, pullout: float, times: dict):
    """A finished dislodging case directory: its metrics and the pulls it made (force -> time or None)."""
    directory = tmp_path / f"{number}-{method}-{hz:g}"
    directory.mkdir()
    metrics = {"threshold_force_N": threshold, "bracket_N": 0.01, "impulse_at_threshold_Ns": 0.5,
               "quasi_static_pullout_N": pullout, "one_dof_first_slip_N": 1.0, "one_dof_full_slide_N": 2.0}
    (directory / "result.json").write_text(json.dumps({"status": "ok", "reason": None, "metrics": metrics}))
    with open(directory / "pulls.csv", "w", newline="") as stream:
        writer = csv.DictWriter(stream, fieldnames=dislodging.pull_columns(), extrasaction="ignore")
        writer.writeheader()
        for force, time in times.items():
            writer.writerow({"case": number, "method": method, "pulse_hz": hz if method == "pulse" else "",
                             "force_N": force, "dislodged": time is not None, "dislodge_time_s": time or "",
                             "thickness_mm": 1.0})
    scene = {"dislodging": {"case": number, "method": method, "pulse_hz": hz, "rotation": "free", "thickness": 1.0}}
    return SimpleNamespace(dir=directory, scene=scene)


def test_dislodging_summary_leads_with_the_thresholds(tmp_path):
    cases = [case(tmp_path, 1, "continuous", 0.0, 20.5, 20.0, {20.4: None, 20.5: 0.031, 23.0: 0.012}),
             case(tmp_path, 1, "pulse", 50.0, 21.0, 20.0, {21.0: 0.052, 20.9: None})]
    blocks = dislodging.summary_blocks(SimpleNamespace(cases=cases))
    kind, header, body = blocks[-1]
    assert kind == "table" and header[:2] == ["threshold pull (N)", "threshold bracket (N)"]
    assert header[-5:] == ["thesis case", "pull", "pulse frequency (Hz)", "peg rotation in the pull", "thickness (mm)"]
    column = {name: k for k, name in enumerate(dislodging.SUMMARY_COLUMNS)}
    continuous, pulsed = body
    assert continuous[column["threshold_force_N"]] == "20.5" and continuous[column["time_at_threshold_s"]] == "0.031"
    assert pulsed[column["time_at_threshold_s"]] == "0.052" and pulsed[column["pulse_hz"]] == "50"
    assert float(continuous[column["threshold_over_pullout"]]) == pytest.approx(20.5 / 20.0, rel=1e-3)
    assert continuous[column["thesis_threshold_N"]] == "20.2"  # the thesis' continuous threshold, case 1
