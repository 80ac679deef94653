"""The discrete problem and its solution: forms from the effects, Schur-complement Newton, stepping, loads."""
