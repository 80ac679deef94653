"""`history.csv`, streamed: one flushed row per converged increment, so a run that is
killed or fails keeps every increment it finished (written on rank 0)."""
import csv
from pathlib import Path

from femcontact.io import WriteError, describe


class HistoryWriter:
    """Appends rows to a CSV file; the first row fixes the columns. A failed write (disk full,
    read-only) stops the writing and is kept in `error` (a WriteError naming the file) for the
    caller to raise on every rank once the ranks are in step."""

    def __init__(self, path: Path, rank: int = 0):
        self.path, self.rank = Path(path), rank
        self.stream = self.writer = None
        self.error = None

    def __call__(self, row: dict, cuts: int = 0) -> None:
        if self.rank != 0 or self.error is not None:
            return
        try:
            if self.writer is None:
                self.stream = open(self.path, "w", newline="")
                self.writer = csv.DictWriter(self.stream, fieldnames=list(row), extrasaction="ignore")
                self.writer.writeheader()
            self.writer.writerow(row)
            self.stream.flush()
        except OSError as error:
            self.error = WriteError(describe(error, self.path))

    def close(self) -> None:
        if self.stream is not None:
            try:
                self.stream.close()
            except OSError as error:
                self.error = self.error or WriteError(describe(error, self.path))
