"""A run's outcome, the `status` of its result.json."""

STATUSES = ("ok", "no_equilibrium", "failed")
"""Solved; answered that a load has no static equilibrium (the reason names the step, the load and
the friction it needs); failed (the reason says where and why)."""
ANSWERS = STATUSES[:2]
"""Statuses of a run that answered: exit code 0, complete in a study (not retried as failures)."""
