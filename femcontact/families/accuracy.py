"""What the families' rows in `make accuracy` share: the repository's root, where their scenes are
read from (the Richardson extrapolation they measure errors against is references.richardson)."""
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
"""The repository: scenes/ and studies/ are read from it."""
