"""A scene made discrete: `Problem` (unknowns, the effects' terms, compiled forms, and the physical
scales a solver needs) and `Schedule` (the scene's steps as loads at any time). The solver sees
these, never the scene."""
