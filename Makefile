# masonry_fdem — two commands: `make demo` and `make test`.
# Both create .venv on first use with a Python >= 3.12 found on the machine and install
# the package with its test extras and dolfinx from the dolfinx-solver-real wheel.
# Override the interpreter with `make PYTHON=/path/to/python3.12 test`.

VENV ?= .venv
NP ?= 2
PY := $(VENV)/bin/python
MPIRUN := $(VENV)/bin/mpirun
# an existing conda/Docker dolfinx: `make test VENV_FLAGS=--system-site-packages EXTRAS=test`
EXTRAS ?= test,wheel
VENV_FLAGS ?=

.PHONY: demo demo-search demo-trl demo-bridge demo-bridge-collapse demo-chimney test test-serial test-parallel precompile bench clean venv

PYTHON ?= $(shell bash tools/find_python.sh)

venv: $(VENV)/.installed

$(VENV)/.installed: pyproject.toml
	@if [ -z "$(PYTHON)" ]; then echo "error: no Python >= 3.12 found (set PYTHON=...)"; exit 1; fi
	@echo "using $(PYTHON)"
	test -x $(PY) || $(PYTHON) -m venv $(VENV_FLAGS) $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[$(EXTRAS)]"
	touch $@

precompile: venv
	$(PY) -m masonry_fdem.precompile

demo: precompile
	$(MPIRUN) -n $(NP) $(PY) demos/repair_arch.py --out out_repair_arch
	$(MPIRUN) -n $(NP) $(PY) demos/settle_arch.py --out out_settle_arch
	$(MPIRUN) -n $(NP) $(PY) demos/topple_wall.py --out out_topple_wall
	$(MPIRUN) -n $(NP) $(PY) demos/shear_wall.py --out out_shear_wall
	$(MPIRUN) -n $(NP) $(PY) demos/materials.py --out out_materials
	$(MPIRUN) -n $(NP) $(PY) demos/silo.py --out out_silo
	$(MPIRUN) -n $(NP) $(PY) demos/trl_arch.py --coarse --out out_trl_coarse
	$(MPIRUN) -n $(NP) $(PY) demos/bridge.py --coarse --out out_bridge_coarse

# the TRL three-ring arch with its fill, unstrengthened and anchored, one rank each
# (issue #21; under 9 minutes on 2 cores; unstrengthened *peak passed* 64.29 kN, anchored
# *not converged* at 81.2 mm with 102.64 kN carried: docs/trl.md)
demo-trl: precompile
	$(MPIRUN) -n $(NP) $(PY) demos/trl_arch.py --out out_trl

# arch bridges with fill (issue #22): the reference paper's two-span bridge with its fill
# as disks, a bogie driven across it at a fixed load, seven positions (about 6 minutes on
# 2 cores); then a single span, collapse load against the axle's position, eight
# positions, with Mohr-Coulomb fill and bare (about 5 minutes)
demo-bridge: precompile
	$(MPIRUN) -n $(NP) $(PY) demos/bridge_two_span_disks.py --out out_bridge_two_span_disks
	$(MPIRUN) -n $(NP) $(PY) demos/bridge.py --out out_bridge

# the two-span bridge with Mohr-Coulomb fill loaded to collapse at four positions of the
# bogie, one rank per position (10-20 minutes on 2 cores)
demo-bridge-collapse: precompile
	$(MPIRUN) -n $(NP) $(PY) demos/bridge_two_span.py --out out_bridge_two_span

# the chimney demolition of the reference paper (issue #23): a 30 m brick chimney felled
# by a notch at its base, falling and breaking up on the ground (explicit dynamics)
demo-chimney: precompile
	$(MPIRUN) -n $(NP) $(PY) demos/chimney.py --out out_chimney

# a small anchor layout search, then layouts per hour on the reference arch (under a
# minute on 2 cores)
demo-search: precompile
	$(MPIRUN) -n $(NP) $(PY) demos/anchor_search.py --out out_anchor_search

test: test-serial test-parallel

# one process per test (MPI.COMM_WORLD of size 1), two tests at a time: pytest-xdist
# workers, a test file to a worker (its module fixtures made once)
test-serial: precompile
	$(PY) -m pytest tests -q -n $(NP) --dist loadfile

test-parallel: precompile
	$(MPIRUN) -n $(NP) $(PY) -m pytest tests -q -p no:cacheprovider

bench: precompile
	$(PY) benchmarks/step_cost.py

clean:
	rm -rf $(VENV) out_* .pytest_cache
