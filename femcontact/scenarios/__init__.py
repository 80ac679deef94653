"""Measurement programs (`make bench`, `make accuracy`, `make stability`, `make plasticity`) and the
implicit-Euler time integrator with events (`dynamics.py`)."""
