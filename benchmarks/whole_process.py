"""A scene run as whole `mpirun -n R femcontact run` processes, timed like a user's run (start-up
included): the benchmark's and the accuracy study's 3-D rows."""
import json
import os
import subprocess
import sys
import time
from pathlib import Path


def run_scene(scene: Path, ranks: int, out: Path, settings: dict) -> tuple[dict, float]:
    """Run `scene` with `--set key=value` per setting, writing to `out`; returns its result.json
    (status 'no result' if it wrote none) and the wall time (s)."""
    command = ["mpirun", "-n", str(ranks), sys.executable, "-m", "femcontact", "run", str(scene)]
    for key, value in settings.items():
        command += ["--set", f"{key}={value}"]
    path = Path(out) / "result.json"
    path.unlink(missing_ok=True)  # a run that writes no result must not be read as the last one's
    start = time.perf_counter()
    # env: Python's view of the environment; the variables MPI adds to an initialised process's
    # C environment make a child `mpirun` fail at once
    subprocess.run(command + ["--out", str(out), "--quiet"], check=False, env=dict(os.environ))
    wall = time.perf_counter() - start
    result = json.loads(path.read_text()) if path.exists() else {"status": "no result", "info": {}, "metrics": {}}
    return result, wall
