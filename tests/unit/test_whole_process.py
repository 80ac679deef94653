"""A whole-process benchmark run (benchmarks/whole_process.py, the 3-D rows of `make bench` and
`make accuracy`) reads only the result its own process wrote: one that ends before writing a
result is reported as 'no result', not as the result an earlier run left in the same folder."""
import json

from benchmarks.whole_process import run_scene


def test_a_run_that_writes_no_result_does_not_read_the_last_one(tmp_path):
    (tmp_path / "result.json").write_text(json.dumps({"status": "ok", "info": {"dofs": 1}, "metrics": {}}))
    result, wall = run_scene(tmp_path / "no_such_scene.toml", 1, tmp_path, {})
    assert result["status"] == "no result"
    assert not (tmp_path / "result.json").exists()
    assert wall > 0
