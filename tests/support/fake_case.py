"""Stand-in for `[mpirun -n K] femcontact run scene.toml --out DIR --quiet` in the study runner's tests.

Usage: fake_case.py [-n K] FEMCONTACT run SCENE --out DIR [--quiet] [--checkpoint] [--restart DIR]
(or, in a warm worker, `fake_case:worker_main`)
(`-n K` imitates a launcher; FEMCONTACT, the program the runner asks for, is ignored.)

Writes DIR/result.json like `femcontact run` (atomically, last) with metrics computed
from the scene: load = -steps[0].force[1], product = contact.mu * contact.gamma.
Environment knobs:
  FAKE_CALLS  directory: one file per invocation (to count them)
  FAKE_SLEEP  seconds to sleep before writing the result
  FAKE_FAIL_MU  contact.mu for which the case raises (exit 1, result 'failed')
  FAKE_NO_EQUILIBRIUM_MU  contact.mu for which the case ends 'no_equilibrium' (exit 0)
  FAKE_CRASH_MU contact.mu for which the process dies without a result
  FAKE_HANG_MU  contact.mu for which the case sleeps forever
  FAKE_RANKS  expected MPI size: run under a real mpirun and check it with mpi4py
  FAKE_FIELDS write a synthetic fields.npz (2 or 3 = dimension)
--checkpoint writes DIR/checkpoint/state; --restart CHECKPOINT requires CHECKPOINT/state.
"""
import json
import os
import sys
import time
import tomllib
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))


def main(argv):
    ranks, rank = 1, 0
    if argv[0] == "-n":
        ranks, argv = int(argv[1]), argv[2:]
    if os.environ.get("FAKE_RANKS"):
        from mpi4py import MPI

        ranks, rank = MPI.COMM_WORLD.size, MPI.COMM_WORLD.rank
        assert ranks == int(os.environ["FAKE_RANKS"]), f"expected {os.environ['FAKE_RANKS']} ranks, got {ranks}"
    _, command, scene_path, *rest = argv
    assert command == "run", argv
    out = Path(rest[rest.index("--out") + 1])
    scene = tomllib.loads(Path(scene_path).read_text())
    mu = scene["contact"]["mu"]
    if os.environ.get("FAKE_CALLS") and rank == 0:
        Path(os.environ["FAKE_CALLS"], f"{out.resolve().name}.{os.getpid()}").write_text(" ".join(rest))
    if "--restart" in rest:
        assert Path(rest[rest.index("--restart") + 1], "state").exists(), "restart from a missing checkpoint"
    start = time.perf_counter()
    time.sleep(float(os.environ.get("FAKE_SLEEP", 0)))
    if str(mu) == os.environ.get("FAKE_HANG_MU"):
        time.sleep(3600)
    if str(mu) == os.environ.get("FAKE_CRASH_MU"):
        print("fake case: segmentation fault (pretend)")
        os._exit(139)
    if os.environ.get("FAKE_FIELDS") and rank == 0:
        from synthetic_fields import write_fields

        write_fields(out / "fields.npz", dim=int(os.environ["FAKE_FIELDS"]))
    failed = str(mu) == os.environ.get("FAKE_FAIL_MU")
    loose = str(mu) == os.environ.get("FAKE_NO_EQUILIBRIUM_MU")
    result = {"status": "failed" if failed else "no_equilibrium" if loose else "ok",
              "reason": f"NewtonDiverged: no convergence at mu = {mu}" if failed else
              f"step 'press': the load needs mu >= 0.5, the scene has mu = {mu}" if loose else None,
              "metrics": {} if failed else {"load": -scene["steps"][0]["force"][1],
                                            "product": mu * scene["contact"]["gamma"]},
              "timings": {"solve": time.perf_counter() - start, "total": time.perf_counter() - start},
              "info": {"ranks": ranks, "dofs": 1000, "newton_iterations": 7, "effects": scene["effects"],
                       "args": rest}}
    if "--checkpoint" in rest and rank == 0:
        (out / "checkpoint").mkdir(exist_ok=True)
        (out / "checkpoint" / "state").write_text("steps done")
    if rank == 0:
        tmp = out / ".result.json.tmp"
        try:
            tmp.write_text(json.dumps(result))
            os.replace(tmp, out / "result.json")
        finally:
            tmp.unlink(missing_ok=True)  # as `femcontact run`: no temporary left on a full disk
    return 1 if failed else 0


def worker_main(argv):
    """main() as a study's warm worker calls it (femcontact/study/workers.py): femcontact's arguments."""
    return main(["femcontact", *argv])


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
