"""The product speaks to its user: no development history in code, scenes, studies, Makefile,
README or docs.

A reader has no use for work-item numbers, for who ran what in which session, for branches and
merges, or for the commit a number was measured at: a number names the command that reproduces
it. The patterns are phrases of the development process only, so physics text ("the one-point
branch", "a gmsh session", "results merged") does not match them.
"""
import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CHECKED = ("femcontact/", "geometry/", "benchmarks/", "tests/", "scenes/", "studies/", "docs/")
CHECKED_FILES = ("Makefile", "README.md", "pyproject.toml", "CITATION.cff")
SUFFIXES = {".py", ".toml", ".md", ".cff", ".sh", ".txt", ""}
HEX = r"(?=[0-9a-f]*\d)[0-9a-f]{7,40}\b"  # an abbreviated or full commit hash

HISTORY = re.compile("|".join([
    r"\bissues?\s+#?\d+",                                      # work items: "issue 12"
    r"\bgoals? of (the )?issue\b",
    r"(?:^|[\s(\[])#\d{1,4}\b(?![;\w])",                       # "#12" (not a colour "#222;")
    r"\bpull request\b",
    r"\bthe issue's\b|\(issue\)",
    r"\b(this|that|an earlier|a previous|the previous|another|a later|the next) session('s)?\b",
    r"\b(other |a |the )?helpers?'s? (branch|jobs?|runs?|work|session)\b",
    r"\bother helpers\b",
    r"\b(this|that|my|our|a helper's|the helper's) branch\b",
    r"\bmerg(e|ed|ing)\s+(with |from |into )?main\b",
    r"\b(before|after) (the|that|its|this) (last )?merge\b",
    r"\bmain's\b",
    r"\bworktree\b",
    r"\b(to|by|for|with) the lead\b",
    r"\b(before|after) this (change|work|commit|session)\b",
    r"\b(broke|failed|used to \w+)\s[\w\s]{0,40}\bbefore\s+this\b",   # "broke whole sweeps before this"
    r"\bnot (been )?tried yet\b",
    r"\bcommit\s+" + HEX,
    r"\bclone (of|at)\s+" + HEX,
    r"\b(working )?tree of\s+" + HEX,
    r"\bat (?=[0-9a-f]*[a-f])" + HEX,                          # "at 1c483a5" (a hash, not a number)
    r"\breference \u00a7\s*\d",                                  # a source the user does not have: name it
]), re.IGNORECASE)


def checked_files() -> list[Path]:
    """The tracked text files of the product (the working tree when git is not available)."""
    try:
        names = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True,
                               check=True).stdout.splitlines()
    except (OSError, subprocess.CalledProcessError):
        names = [p.relative_to(ROOT).as_posix() for p in ROOT.rglob("*") if p.is_file()]
    this = Path(__file__).resolve().relative_to(ROOT).as_posix()
    return [ROOT / name for name in names
            if (name.startswith(CHECKED) or name in CHECKED_FILES) and name != this
            and not name.startswith("tests/data/") and Path(name).suffix in SUFFIXES
            and (ROOT / name).is_file()]


def history_lines(path: Path) -> list[str]:
    """'FILE:LINE: phrase' for each match, also of a phrase broken across lines."""
    text = path.read_text(errors="replace")
    return [f"{path.relative_to(ROOT)}:{text.count(chr(10), 0, match.start()) + 1}: {' '.join(match.group().split())}"
            for match in HISTORY.finditer(text)]


def test_no_development_history_in_the_product():
    files = checked_files()
    assert len(files) > 100, "the file list is empty or cut short"
    hits = [hit for path in files for hit in history_lines(path)]
    assert not hits, "development history (say what it does and the command that measures it):\n" + "\n".join(hits)


def test_the_patterns_catch_history_and_spare_physics():
    history = ["the solver change of issue 12", "Goals of issue 12", "see #14 for", "this session's solver",
               "other helpers' jobs", "this branch merged with main's update", "before the last merge",
               "reported to the lead", "from a clean clone of 1225964", "(commit e18e21b)", "at 1c483a5",
               "before this change", "the working tree of b53d2e2",
               "the issue's Moreau-Jean option", "0.63 of the thesis' (issue)", "(reference \u00a75)",
               "a compilation in progress broke whole sweeps before this", "a path not tried yet"]
    physics = ["the one-point branch closes", "a quiet gmsh session", "no helper daemon",
               "cases before duplicates are merged", "color: #222;", "at 1000000 N", "the chamfer branch",
               "the leading dim x dim block", "GetFEM merges regions", "in its own session",
               "the increment before this one failed", "tried on the failing case"]
    assert [s for s in history if not HISTORY.search(s)] == []
    assert [s for s in physics if HISTORY.search(s)] == []
