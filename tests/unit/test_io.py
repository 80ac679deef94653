"""The readers of what a run writes (femcontact/io.py): one CSV reader for every CSV file, and a
case's result.json."""
import json

from femcontact.io import read_csv, read_result
from femcontact.outputs.history import HistoryWriter, read_history


def test_one_reader_gives_texts_or_numbers_and_skips_comment_lines(tmp_path):
    path = tmp_path / "pulls.csv"
    path.write_text("# source: a published table\ncase,force_N,dislodged,note\n1,7.5,True,\n2,-1e-3,False,x y\n")
    assert read_csv(path, comments=True) == [{"case": "1", "force_N": "7.5", "dislodged": "True", "note": ""},
                                             {"case": "2", "force_N": "-1e-3", "dislodged": "False", "note": "x y"}]
    assert read_csv(path, numbers=True, comments=True)[1] == {"case": 2.0, "force_N": -0.001, "dislodged": "False",
                                                              "note": "x y"}


def test_history_reads_back_as_columns(tmp_path):
    writer = HistoryWriter(tmp_path / "history.csv")
    writer({"step": "load", "time": 0.5, "tilt": 1.25, "stuck": True})
    writer({"step": "release", "time": 1.0, "tilt": float("nan"), "stuck": False})
    writer.close()
    history = read_history(tmp_path / "history.csv")
    assert list(history["step"]) == ["load", "release"] and list(history["stuck"]) == [1.0, 0.0]
    assert history["time"].tolist() == [0.5, 1.0] and history["tilt"][0] == 1.25


def test_a_case_without_a_whole_result_has_none(tmp_path):
    assert read_result(tmp_path) is None
    (tmp_path / "result.json").write_text('{"status": "ok"')  # cut short
    assert read_result(tmp_path) is None
    (tmp_path / "result.json").write_text(json.dumps({"status": "ok"}))
    assert read_result(tmp_path) == {"status": "ok"}
