"""A family's report across several of its studies: `python -m femcontact.study.gathering NAME
[--results results]` reads the cases of the study files the family's `Gathering` NAME names (those
each file makes now, not every case directory on disk) and hands those that ended ok to the
family, which writes results/NAME/ (the Makefile runs it after the studies).
"""
import argparse
from pathlib import Path

from femcontact import families
from femcontact.io import read_result
from femcontact.study.study_file import load_study


def ok_cases(study_file: Path, results: Path) -> list[tuple]:
    """(case, metrics) of the study's cases that ended ok."""
    study = load_study(study_file, results_root=results)
    return [(case, result["metrics"]) for case in study.cases
            if (result := read_result(case.dir)) and result["status"] == "ok"]


def gather(name: str, results: Path) -> Path:
    """Write the gathering `name` into results/NAME/ and return that directory."""
    gathering = families.gatherings()[name]
    out = results / gathering.name
    out.mkdir(parents=True, exist_ok=True)
    gathering.write({path.stem: ok_cases(path, results) for path in gathering.studies}, out)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m femcontact.study.gathering",
                                     description="Write a family's report across several of its studies "
                                                 "into RESULTS/NAME/.")
    parser.add_argument("name", choices=sorted(families.gatherings()), help="the gathering")
    parser.add_argument("--results", default="results", help="results root of its studies (default: results)")
    args = parser.parse_args(argv)
    gather(args.name, Path(args.results))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
