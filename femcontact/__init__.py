"""femcontact: FEniCSx parametric studies of peg-in-hole contact mechanics.

Units throughout: mm, N, N*mm, s, MPa, t/mm^3.
"""
__version__ = "0.1.0"
