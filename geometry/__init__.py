"""gmsh builders for peg/hole geometries (2-D sections and 3-D), returning DOLFINx meshes with tags."""
