"""Studies: the study file, the runner, the results database and the report."""
