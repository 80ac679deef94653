"""Physics as small functions and classes: elastic laws, rotations, the rigid body, signed distances, Newmark."""
