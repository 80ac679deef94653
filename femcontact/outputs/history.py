"""`history.csv`, streamed: one row per converged increment, handed to the kernel at once, so
a run that is killed or fails keeps every increment it finished (written on rank 0); and read
back as columns (`read_history`)."""
import csv
import io
import math
import os
from pathlib import Path

from femcontact.io import WriteError, describe, read_csv


class HistoryWriter:
    """Appends rows to a CSV file; the first row fixes the columns. A failed write (disk full,
    read-only) cuts the file back to its last whole row, stops the writing and is kept in
    `error` (a WriteError naming the file) for the caller to raise on every rank once the
    ranks are in step."""

    def __init__(self, path: Path, rank: int = 0):
        self.path, self.rank = Path(path), rank
        self.fd = self.columns = None
        self.written = 0  # bytes of whole rows in the file
        self.error = None

    def __call__(self, row: dict, cuts: int = 0) -> None:
        if self.rank != 0 or self.error is not None:
            return
        text = io.StringIO()
        writer = csv.DictWriter(text, fieldnames=self.columns or list(row), extrasaction="ignore")
        if self.columns is None:
            writer.writeheader()
        writer.writerow(row)
        data = text.getvalue().encode()
        try:
            if self.fd is None:
                self.fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
                self.columns = list(row)
            view = memoryview(data)
            while view:
                view = view[os.write(self.fd, view):]
        except OSError as error:
            self.error = WriteError(describe(error, self.path))
            if self.fd is not None:
                try:
                    os.ftruncate(self.fd, self.written)  # no half row
                except OSError:
                    pass
            return
        self.written += len(data)

    def close(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None


def read_history(path) -> dict:
    """A history.csv (or any CSV of rows) as {column: numpy array} (see `columns`)."""
    return columns(read_csv(path))


def columns(rows: list[dict]) -> dict:
    """Rows of strings (a CSV file's) as {column: numpy array}: floats where every filled cell is a
    number (True/False as 1/0, empty cells NaN), else the texts."""
    names = {}
    for row in rows:
        names.update(dict.fromkeys(row))
    return {name: _column([row.get(name) for row in rows]) for name in names}


def _column(cells: list):
    import numpy as np

    def number(cell):
        if cell is None or cell == "":
            return math.nan
        if cell in ("True", "False"):
            return float(cell == "True")
        return float(cell)

    try:
        return np.array([number(cell) for cell in cells], dtype=float)
    except (TypeError, ValueError):
        return np.array(["" if cell is None else str(cell) for cell in cells], dtype=object)
