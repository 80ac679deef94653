"""A study's progress as its cases finish: a bar on a terminal, else a line per case."""
import sys
import time

from femcontact.study.study_file import Case, describe_params


class Progress:
    """On a terminal a progress bar (and a line per failure), otherwise a line per finished case;
    nothing with --quiet."""

    def __init__(self, total: int, quiet: bool, stream=sys.stderr):
        self.total, self.quiet, self.stream = total, quiet, stream
        self.bar = not quiet and stream.isatty()
        self.done = self.failed = 0
        self.start = time.monotonic()
        self.drawn = 0.0

    def finished(self, case: Case, result: dict, prefix: bool = False) -> None:
        if not prefix:
            self.done += 1
            self.failed += result["status"] == "failed"
        if self.quiet or (self.bar and result["status"] == "ok"):
            return
        what = f"prefix {case.id}" if prefix else f"{case.id} {describe_params(case.params)}"
        line = f"[{self.done}/{self.total}] {result['status']:6s} {what}"
        if result["status"] != "ok":
            line += f": {result['reason']}"
        self._clear()
        print(line, file=self.stream, flush=True)
        self.drawn = 0.0

    def update(self, running: list) -> None:
        """Redraw the bar (at most every 0.2 s) with the number of `running` jobs."""
        now = time.monotonic()
        if not self.bar or now - self.drawn < 0.2:
            return
        self.drawn = now
        elapsed = now - self.start
        eta = f"{_duration(elapsed / self.done * (self.total - self.done))}" if self.done else "?"
        filled = int(30 * self.done / max(self.total, 1))
        self.stream.write(f"\r[{'#' * filled}{'.' * (30 - filled)}] {self.done}/{self.total} done, "
                          f"{self.failed} failed, {len(running)} running, {_duration(elapsed)} elapsed, "
                          f"ETA {eta}\x1b[K")
        self.stream.flush()

    def close(self) -> None:
        """Leave the terminal's last line free for the summary."""
        self._clear()

    def _clear(self) -> None:
        if self.bar:
            self.stream.write("\r\x1b[K")
            self.stream.flush()


def _duration(seconds: float) -> str:
    seconds = int(seconds)
    return f"{seconds // 3600}h{seconds % 3600 // 60:02d}m" if seconds >= 3600 else \
        f"{seconds // 60}m{seconds % 60:02d}s" if seconds >= 60 else f"{seconds}s"
