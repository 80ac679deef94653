"""Where the families and the measurement programs read the repository's own files: the example
scenes and the study files."""
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
"""The repository femcontact is installed from (editable)."""
SCENES = ROOT / "scenes"
STUDIES = ROOT / "studies"
