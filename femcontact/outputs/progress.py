"""Progress of a run, one increment at a time, on rank 0's standard error.

On a terminal a single status line is redrawn; otherwise (a log file, a study's case
log) one line per increment: step, time, dt, Newton iterations and cuts so far.
"""
import sys
import time


class Progress:
    def __init__(self, scene: dict, stream=sys.stderr, rank: int = 0):
        self.stream, self.rank = stream, rank
        self.total_time = sum(step["duration"] for step in scene["steps"])
        self.names = [step["name"] for step in scene["steps"]]
        self.tty = stream.isatty()
        self.start = time.perf_counter()
        self.increments = 0

    def __call__(self, row: dict, cuts: int = 0) -> None:
        if self.rank != 0:
            return
        self.increments += 1
        step = row["step"]
        index = self.names.index(step) + 1 if step in self.names else 0
        fraction = row["time"] / self.total_time if self.total_time > 0 else 1.0
        line = (f"[{fraction:6.1%}] step {index}/{len(self.names)} {step!r} t = {row['time']:.6g} s "
                f"dt = {row['dt']:.3g} s newton {row['newton_iterations']} cuts {cuts} "
                f"({time.perf_counter() - self.start:.1f} s)")
        if self.tty:
            self.stream.write("\r\033[K" + line)
        else:
            self.stream.write(line + "\n")
        self.stream.flush()

    def close(self) -> None:
        if self.rank == 0 and self.tty and self.increments:
            self.stream.write("\n")
            self.stream.flush()
