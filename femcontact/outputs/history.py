"""`history.csv`, streamed: one flushed row per converged increment, so a run that is
killed or fails keeps every increment it finished (written on rank 0)."""
import csv
from pathlib import Path


class HistoryWriter:
    """Appends rows to a CSV file; the first row fixes the columns."""

    def __init__(self, path: Path, rank: int = 0):
        self.path, self.rank = Path(path), rank
        self.stream = self.writer = None

    def __call__(self, row: dict, cuts: int = 0) -> None:
        if self.rank != 0:
            return
        if self.writer is None:
            self.stream = open(self.path, "w", newline="")
            self.writer = csv.DictWriter(self.stream, fieldnames=list(row), extrasaction="ignore")
            self.writer.writeheader()
        self.writer.writerow(row)
        self.stream.flush()

    def close(self) -> None:
        if self.stream is not None:
            self.stream.close()
