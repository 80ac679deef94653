"""The rigid body's degrees of freedom, by dimension: what `rigid_body.dofs`, `steps[].motion` and
`steps[].support_motion` are keyed by, and the order of the rigid unknowns (translations in mm,
then rotations in rad)."""

RIGID_DOFS = {2: ("x", "y", "rz"), 3: ("x", "y", "z", "rx", "ry", "rz")}
