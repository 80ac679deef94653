"""The results database of a study: `results/NAME/results.sqlite`, one row per finished case.

The case directories are the truth; the database is an index of them that can
always be rebuilt (`Database.rebuild`, done at the start of every `femcontact
study`), so it never disagrees with them. A row is written in one transaction,
after the case's `result.json` is in place.

Table `cases`, columns in CSV order:
  case_id, status,
  the swept keys under their dotted scene keys (lists and tables as JSON),
  one column per metric (named as the metric; `metric.NAME` if that name is taken),
  `time.PHASE` per timing phase (mesh, compile, assembly, solve, ..., total),
  ranks, dofs, newton_iterations, active_effects, reason,
  python, dolfinx, petsc4py, numpy, mpi4py, git_commit, wall (runner's wall time of the case, s),
  scene (the full resolved scene as JSON; not exported to CSV).
"""
import contextlib
import csv
import json
import os
import sqlite3
import tomllib
from pathlib import Path

from femcontact.io import WriteError, write_atomic

HEAD = ("case_id", "status")
INFO = ("ranks", "dofs", "newton_iterations", "active_effects", "reason")
PROVENANCE = ("python", "dolfinx", "petsc4py", "numpy", "mpi4py", "git_commit", "wall")


def _sql(value):
    """A value SQLite stores as is: numbers and strings; anything else as JSON."""
    if value is None or isinstance(value, (int, float, str)):
        return int(value) if isinstance(value, bool) else value
    return json.dumps(value)


def _quote(name: str) -> str:
    return '"' + name.replace('"', '""') + '"'


def case_row(case_dir: Path, parameters: dict) -> dict | None:
    """The database row of a case directory, or None if the case has no result."""
    try:
        result = json.loads((case_dir / "result.json").read_text())
    except (FileNotFoundError, json.JSONDecodeError):
        return None
    info = result.get("info", {})
    try:
        runner = json.loads((case_dir / "runner.json").read_text())
    except FileNotFoundError:
        runner = {}
    try:
        scene = tomllib.loads((case_dir / "scene.toml").read_text())
    except FileNotFoundError:
        scene = None
    row = {"case_id": case_dir.name, "status": result["status"], **parameters}
    taken = set(HEAD) | set(INFO) | set(PROVENANCE) | set(parameters) | {"scene"}
    for name, value in result.get("metrics", {}).items():
        row[f"metric.{name}" if name in taken or name.startswith("time.") else name] = value
    for phase, seconds in result.get("timings", {}).items():
        row[f"time.{phase}"] = seconds
    row.update(ranks=info.get("ranks"), dofs=info.get("dofs"), newton_iterations=info.get("newton_iterations"),
               active_effects=info.get("effects"), reason=result.get("reason"))
    row.update({name: runner.get(name) for name in PROVENANCE})
    row["scene"] = scene
    return {name: _sql(value) for name, value in row.items()}


class Database:
    """SQLite index of a study's case directories; `parameters` are the swept keys."""

    def __init__(self, path, parameters: list[str]):
        self.path = Path(path)
        self.parameters = list(parameters)
        try:
            self.connection = sqlite3.connect(self.path, isolation_level=None)  # explicit transactions
            self.connection.execute("PRAGMA journal_mode=WAL")
            # commits without fsync (WAL stays consistent; a power cut may lose the last rows, which
            # the next run rebuilds from the case directories)
            self.connection.execute("PRAGMA synchronous=NORMAL")
        except sqlite3.Error as error:
            where = "" if os.access(self.path.parent, os.W_OK) else f"; {self.path.parent} is not writable"
            raise WriteError(f"{self.path}: cannot write the results database ({error}{where})") from None

    def close(self) -> None:
        self.connection.close()

    def columns(self) -> list[str]:
        return [row[1] for row in self.connection.execute("PRAGMA table_info(cases)")]

    def rebuild(self, cases) -> None:
        """Drop every row and re-read the case directories of `cases` (objects with .dir and .params)."""
        rows = [row for row in (case_row(case.dir, case.params) for case in cases) if row is not None]
        with self._transaction():
            self.connection.execute("DROP TABLE IF EXISTS cases")
            fixed = [*HEAD, *self.parameters, *INFO, *PROVENANCE, "scene"]
            self.connection.execute(f"CREATE TABLE cases ({', '.join(map(_quote, fixed))}, PRIMARY KEY (case_id))")
            for row in rows:
                self._insert(row)

    def record(self, case) -> None:
        """Write (or replace) the row of a finished case, in one transaction."""
        row = case_row(case.dir, case.params)
        if row is not None:
            with self._transaction():
                self._insert(row)

    def _insert(self, row: dict) -> None:
        existing = set(self.columns())
        for name in [name for name in row if name not in existing]:  # metrics in the order the case gives
            self.connection.execute(f"ALTER TABLE cases ADD COLUMN {_quote(name)}")
        names = ", ".join(map(_quote, row))
        self.connection.execute(f"INSERT OR REPLACE INTO cases ({names}) VALUES ({', '.join('?' * len(row))})",
                                list(row.values()))

    @contextlib.contextmanager
    def _transaction(self):
        """All or nothing; a failed write (disk full, read-only) rolls back and raises WriteError."""
        try:
            self.connection.execute("BEGIN IMMEDIATE")
            yield
            self.connection.execute("COMMIT")
        except BaseException as error:
            with contextlib.suppress(sqlite3.Error):
                if self.connection.in_transaction:
                    self.connection.execute("ROLLBACK")
            if isinstance(error, sqlite3.Error):
                raise WriteError(f"{self.path}: cannot write the results database ({error})") from None
            raise

    def csv_columns(self) -> list[str]:
        """Columns in export order: head, parameters, metrics, timings, info, provenance (no scene)."""
        columns = self.columns()
        fixed = {*HEAD, *self.parameters, *INFO, *PROVENANCE, "scene"}
        metrics = [c for c in columns if c not in fixed and not c.startswith("time.")]
        timings = [c for c in columns if c.startswith("time.")]
        timings.sort(key=lambda c: c == "time.total")  # total last
        return [*HEAD, *self.parameters, *metrics, *timings, *INFO, *PROVENANCE]

    def rows(self, columns=None) -> list[dict]:
        """Every row as a dict (all columns unless `columns` is given), sorted by parameters then case id."""
        columns = columns or self.columns()
        order = ", ".join(map(_quote, [*self.parameters, "case_id"]))
        cursor = self.connection.execute(f"SELECT {', '.join(map(_quote, columns))} FROM cases ORDER BY {order}")
        return [dict(zip(columns, row)) for row in cursor]

    def export_csv(self, path) -> Path:
        """Write the rows to CSV (atomically) and return its path."""
        columns = self.csv_columns()
        rows = self.rows(columns)

        def write(stream):
            writer = csv.DictWriter(stream, columns)
            writer.writeheader()
            writer.writerows(rows)

        return write_atomic(path, write)
