# femcontact: `make study` and `make test` install what is missing, then run.
# Stamp files in .stamps/ record finished install steps; an interrupted step has
# no stamp and is simply redone (apt and pip repair partial installs themselves).

SHELL := /bin/bash
VENV  := .venv
PY    := $(VENV)/bin/python
FEMCONTACT := $(VENV)/bin/femcontact
STAMPS := .stamps
SUDO  := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
RANKS ?= 2
# Processes the serial tests run in (pytest-xdist): one per core, at most 4 (each takes up to 1.5 GB;
# nproc without OMP_NUM_THREADS, which it would report instead).
TEST_WORKERS ?= $(shell n=$$(env -u OMP_NUM_THREADS nproc); echo $$(( n < 4 ? n : 4 )))

APT_PACKAGES := python3-dolfinx python3-gmsh python3-petsc4py python3-mpi4py python3-scipy \
	python3-meshio python3-h5py python3-pytest python3-pytest-xdist python3-venv python3-pip python3-matplotlib \
	openmpi-bin libopenblas0-pthread libgl1 libxrender1 libosmesa6 ffmpeg
PIP_PACKAGES := "numpy<2" "pyvista>=0.45,<0.46" "vtk>=9.4,<9.5"

# Open MPI refuses to run as root unless told; harmless otherwise.
export OMPI_ALLOW_RUN_AS_ROOT := 1
export OMPI_ALLOW_RUN_AS_ROOT_CONFIRM := 1
export OMPI_MCA_rmaps_base_oversubscribe := 1
export OMP_NUM_THREADS := 1
export OPENBLAS_NUM_THREADS := 1
export PYVISTA_OFF_SCREEN := true

STUDY_FILES := $(wildcard studies/*.toml)
STUDIES := $(filter-out dislodging_methods_2d dislodging_methods_3d dislodging_methods_frequency,$(basename $(notdir $(STUDY_FILES))))
DEFAULT_STUDY := wedging

.PHONY: setup test test-serial test-mpi test-slurm test-paraview study docs bench bench_hertz_3d bench_solvers convergence_3d accuracy stability plasticity plasticity_dislodging plasticity_insertion plasticity_wedging rim_3d clean dislodging_methods dislodging_methods_3d dislodging_methods_frequency dislodging_beyond dislodging_beyond_3d dislodging_beyond_frequency $(STUDIES)

setup: $(STAMPS)/venv

$(STAMPS)/apt: Makefile
	@mkdir -p $(STAMPS)
	@if dpkg-query -W -f='$${Status}\n' $(APT_PACKAGES) 2>/dev/null | grep -qv "install ok installed" \
	    || [ "$$(dpkg-query -W -f='$${Status}\n' $(APT_PACKAGES) 2>/dev/null | wc -l)" -lt "$(words $(APT_PACKAGES))" ]; then \
	  echo "== installing Debian packages (a few minutes on a fresh machine)"; \
	  $(SUDO) env DEBIAN_FRONTEND=noninteractive dpkg --configure -a; \
	  $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get update -q; \
	  $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends $(APT_PACKAGES); \
	fi
	@touch $@

$(STAMPS)/venv: $(STAMPS)/apt pyproject.toml
	@echo "== preparing $(VENV) (Debian's DOLFINx + pip-only packages, numpy<2)"
	@[ -x $(PY) ] || /usr/bin/python3 -m venv --system-site-packages $(VENV)
	@$(PY) -m pip install -q --disable-pip-version-check $(PIP_PACKAGES)
	@$(PY) -m pip install -q --disable-pip-version-check --no-deps --no-build-isolation -e .
	@$(PY) -c "import numpy, dolfinx, gmsh, pyvista; assert numpy.__version__ < '2', numpy.__version__"
	@touch $@

test: setup
	$(MAKE) --no-print-directory test-serial test-mpi

test-serial: setup
	$(PY) -m pytest -q -n $(TEST_WORKERS) --dist loadscope tests --ignore=tests/mpi --ignore=tests/slurm

test-mpi: setup
	timeout 1200 mpirun -n 2 $(PY) -m pytest -q -p no:cacheprovider tests/mpi

# Studies through a real SLURM (not part of `make test`; needs root, as slurmd starts the jobs):
# a one-node cluster on localhost (tests/slurm/cluster.sh: munged, slurmctld, slurmd, generated
# config and munge key, all in a temporary directory), the tests of tests/slurm against it, and
# the cluster stopped and removed on any exit.
SLURM_APT_PACKAGES := slurm-wlm munge

# $(call install_missing,PACKAGES,WHAT): apt-get install PACKAGES unless all are installed, then stamp.
define install_missing
	@mkdir -p $(STAMPS)
	@if [ "$$(dpkg-query -W -f='$${Status}\n' $(1) 2>/dev/null | grep -c 'install ok installed')" \
	    -lt "$(words $(1))" ]; then \
	  echo "== installing $(2) (Debian packages)"; \
	  $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get update -q; \
	  $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends $(1); \
	fi
	@touch $@
endef

$(STAMPS)/apt-slurm: Makefile
	$(call install_missing,$(SLURM_APT_PACKAGES),SLURM and munge)

test-slurm: setup $(STAMPS)/apt-slurm
	@cluster=$$(mktemp -d /tmp/femcontact-slurm.XXXXXX); \
	  trap "$(SUDO) tests/slurm/cluster.sh stop $$cluster; $(SUDO) rm -rf $$cluster" EXIT; \
	  echo "== one-node SLURM in $$cluster"; \
	  $(SUDO) tests/slurm/cluster.sh start $$cluster && source $$cluster/env && \
	  PYTHONPATH=$(CURDIR)$${PYTHONPATH:+:$$PYTHONPATH} timeout 900 $(PY) -m pytest -q -p no:cacheprovider tests/slurm

# ParaView itself reads the time series (not part of `make test`): Debian's paraview (pvbatch, with
# python3-paraview) under a virtual X server (xvfb), on a 2-D and a 3-D wedging case written with
# outputs.fields = true; tests/paraview/check_series.py checks frames and arrays and renders the last
# frame to results/paraview/*.png.
PARAVIEW_APT_PACKAGES := paraview python3-paraview xvfb xauth

$(STAMPS)/apt-paraview: Makefile
	$(call install_missing,$(PARAVIEW_APT_PACKAGES),ParaView)

PARAVIEW_CASES := wedging_2d wedging_3d

test-paraview: setup $(STAMPS)/apt-paraview
	@mkdir -p results/paraview
	@for scene in $(PARAVIEW_CASES); do \
	  $(FEMCONTACT) run scenes/$$scene.toml --quiet --set mesh.resolution=0.5 --set outputs.fields=true \
	    --out results/paraview/$$scene || exit $$?; \
	  frames=$$(($$(wc -l < results/paraview/$$scene/history.csv) - 1)); \
	  xvfb-run -a -s "-screen 0 1280x1024x24" pvbatch tests/paraview/check_series.py \
	    results/paraview/$$scene $$frames results/paraview/$$scene.png 2>&1 | grep '^check_series' ; \
	  [ "$${PIPESTATUS[0]}" = 0 ] || exit 1; \
	done

study: $(DEFAULT_STUDY)

# The report is written even when some cases failed (exit 1; not after bad input 2 or Ctrl-C 130);
# the target then fails with the study's status.
# Extra runner options: make NAME STUDY_FLAGS="--retry-failed --jobs 4"
$(STUDIES): %: setup
	@status=0; $(FEMCONTACT) study studies/$@.toml $(STUDY_FLAGS) || status=$$?; \
	  if [ $$status -le 1 ]; then $(FEMCONTACT) report studies/$@.toml || exit $$?; fi; exit $$status

bench: setup
	$(PY) -m benchmarks.bench
	$(PY) -m benchmarks.bench_hertz_3d
	$(PY) -m benchmarks.solver_scaling

# The 3-D Hertz benchmark beside GetFEM alone (also the end of `make bench`): results/bench/hertz_3d.md
bench_hertz_3d: setup
	$(PY) -m benchmarks.bench_hertz_3d

# How a Newton iteration's time and memory grow with the unknowns (3-D wedging, 17k to 1.03M),
# direct and iterative linear solvers, 1 and 2 ranks (also the end of `make bench`): results/bench/solvers.md
bench_solvers: setup
	$(PY) -m benchmarks.solver_scaling

# The 3-D wedging, insertion and snap-fit answers on ladders of meshes (resolution 1 to 4; P2 0.5 to 1.41; 2 ranks)
# with their Richardson extrapolation and discretisation error: results/convergence_3d/convergence_3d.md
convergence_3d: setup
	$(PY) -m benchmarks.convergence_3d

# Plasticity on the wedging case, an edge radius under refinement, its cost; results/plasticity/plasticity.md
plasticity: setup
	$(PY) -m benchmarks.plasticity

# The wedged thesis peg on stainless 316: the least pull that frees it against the least that adds
# 1e-4 of plastic strain, constant and 50 Hz pulses (mesh resolution 0.5); results/plasticity_dislodging/
plasticity_dislodging: setup
	$(PY) -m benchmarks.plasticity_dislodging

# The insertion's chamfer crossing on stainless 316: peak PEEQ and plastic zone against the support's
# stiffness (K_x 20 to 600 N/mm); results/plasticity_insertion/
plasticity_insertion: setup
	$(PY) -m benchmarks.plasticity_insertion

# The wedge map (studies/wedging.toml) elastic and on stainless 316 with plasticity
# (studies/wedging_plastic.toml), paired by map point: wedged, yielded, PEEQ, plastic zone, residual
# force change; results/plasticity_wedging/plasticity_wedging.md (each study's own report in results/STUDY/)
plasticity_wedging: setup
	@status=0; for study in wedging wedging_plastic; do \
	  $(FEMCONTACT) study studies/$$study.toml $(STUDY_FLAGS) || status=$$?; \
	  if [ $$status -gt 1 ]; then exit $$status; fi; \
	  $(FEMCONTACT) report studies/$$study.toml || exit $$?; done; \
	  $(PY) -m femcontact.study.gathering plasticity_wedging || exit $$?; exit $$status

# 3-D wedging: peak von Mises under a sharp and a 1 mm rounded tip rim against the contact element
# size (1 to 0.125 mm), elastic and with plasticity, on $(RANKS) ranks; results/rim_3d/rim_3d.md
rim_3d: setup
	mpirun -n $(RANKS) $(PY) -m benchmarks.rim_3d

# What accuracy costs in time: error against wall time per knob; results/accuracy/accuracy.md
accuracy: setup
	$(PY) -m benchmarks.accuracy --with-3d

# Hard cases stay stable: a seeded random sweep (120 2-D + 12 3-D cases); results/stability/stability.md
stability: setup
	$(PY) -m benchmarks.stability $(STABILITY_FLAGS)

# The measured tables of docs/ (blocks fenced by <!-- generated: results/... --> and <!-- end generated -->)
# refreshed from the results files that name them, docs/scenes.md from the schemas; missing results
# are listed with the target that writes them
docs: setup
	$(PY) -m benchmarks.docs_update

clean:
	rm -rf results

# Ways out of a wedge (degree of wedging, lateral and moment pulses, pull plus shake, the best pulse):
# studies/dislodging_methods_2d.toml, then results/dislodging_methods/; `make dislodging_methods_3d` adds the 3-D
# thresholds (2 ranks), `make dislodging_methods_frequency` the ways out at 10 and 200 Hz and the peak-force optimum.
# `make dislodging_beyond`, `dislodging_beyond_3d` and `dislodging_beyond_frequency` are the same targets.
dislodging_beyond: dislodging_methods
dislodging_beyond_3d: dislodging_methods_3d
dislodging_beyond_frequency: dislodging_methods_frequency
dislodging_methods: STUDY_FILE := studies/dislodging_methods_2d.toml
dislodging_methods_3d: STUDY_FILE := studies/dislodging_methods_3d.toml
dislodging_methods_frequency: STUDY_FILE := studies/dislodging_methods_frequency.toml
dislodging_methods dislodging_methods_3d dislodging_methods_frequency: setup
	@status=0; $(FEMCONTACT) study $(STUDY_FILE) $(STUDY_FLAGS) || status=$$?; \
	  if [ $$status -gt 1 ]; then exit $$status; fi; \
	  $(PY) -m femcontact.study.gathering dislodging_methods || exit $$?; exit $$status
