"""Closed forms from the references (peg-in-hole geometry and wedging, Hertz, Whitney's compliant insertion)."""
