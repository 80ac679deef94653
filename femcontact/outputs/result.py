"""A run's outcome, the `status` of its result.json."""

STATUSES = ("ok", "no_equilibrium", "failed")
"""Solved; answered that a load has no static equilibrium (the reason names the step, the load and
the friction it needs); failed (the reason says where and why)."""
ANSWERS = STATUSES[:2]
"""Statuses of a run that answered: exit code 0, complete in a study (not retried as failures)."""


def status_counts(results) -> dict:
    """{status: number of results} over STATUSES (results without a result file are not counted)."""
    counts = dict.fromkeys(STATUSES, 0)
    for result in results:
        if result is not None:
            counts[result["status"] if result["status"] in counts else "failed"] += 1
    return counts
