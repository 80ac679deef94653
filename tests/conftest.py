"""Test layout: unit/ (one module or rule at a time), verification/ (numbers against analytic
solutions, published tables and convergence), mpi/ (under `mpirun -n 2`), slurm/ (`make
test-slurm`), data/ (published numbers with their source), support/ (a fake case launcher and
synthetic fields files, importable from every test)."""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent / "support"))
