# tengfield: `make run` sets everything up and runs the default scene;
# `make test` sets everything up and runs the whole test suite.
SHELL := /bin/bash
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.tengfield-installed
OUT ?= out
export OMPI_ALLOW_RUN_AS_ROOT := 1
export OMPI_ALLOW_RUN_AS_ROOT_CONFIRM := 1
export OMPI_MCA_rmaps_base_oversubscribe := 1
# the same for OpenMPI 5 (Debian 13), whose launcher (PRRTE) ignores the line above
export PRTE_MCA_rmaps_default_mapping_policy := :oversubscribe
# one machine: Open MPI's TCP transport on the loopback only (Open MPI 5 on Debian 13 printed
# 'Unable to find reachable pairing between local and remote interfaces' for every
# mpirun in a container or chroot that shares the host's interfaces)
export OMPI_MCA_btl_tcp_if_include := lo
# a rank waiting in MPI yields its core (Open MPI busy-polls otherwise): the test suite runs
# mpirun -n 2 beside other processes on this 2-core machine (pytest, the CI's containers)
export OMPI_MCA_mpi_yield_when_idle := 1
export PYVISTA_OFF_SCREEN := true
export MPLBACKEND := Agg

.PHONY: setup system run test test-serial test-mpi test-release test-release-serial test-image test-image-serial test-fast bench clean

setup: $(STAMP)

system:
	bash scripts/install-system.sh

# Debian 12 or 13: scripts/install-system.sh reads /etc/os-release; the venv
# keeps the system numpy's major version (numpy<2 on Debian 12, numpy 2 on 13),
# as printed by scripts/numpy-requirement, because Debian's petsc4py, dolfinx
# and h5py are built against it.
$(STAMP): pyproject.toml scripts/install-system.sh scripts/numpy-requirement
	bash scripts/install-system.sh
	test -x $(PY) || /usr/bin/python3 -m venv --system-site-packages $(VENV)
	$(PY) -m pip install -q --disable-pip-version-check "$$(sh scripts/numpy-requirement)" -e ".[dev]"
	@# a pip h5py (bundled HDF5) would shadow Debian's, which shares dolfinx's HDF5
	$(PY) -m pip uninstall -y -q h5py 2>/dev/null || true
	@# compile the numba kernels now (about 30 s), into numba's cache next to
	@# their sources, so the first `tengfield run` does not pay for it
	$(PY) -m tengfield._warmup
	touch $(STAMP)

run: setup
	$(VENV)/bin/tengfield run -o $(OUT)

test: setup test-serial test-mpi

# the serial suite in one process by default; TEST_JOBS=N spreads it over N pytest-xdist
# workers (a file's tests on one worker, in order). On this 2-core machine that was not
# faster beside CI's containers, and one worker once never ended (.ci/run), so CI runs
# it in one process
TEST_JOBS ?= 1
XDIST = $(if $(filter-out 0 1,$(TEST_JOBS)),-n $(TEST_JOBS) --dist loadfile,)

# TEST_SELECT: a pytest -m expression for the serial suite, empty = every test. .ci/run gives
# the host "not image": the slow tests of tests/conftest.py's IMAGE_SHARE run in the Debian 13
# image instead (make test-image), so that each CI runs every test on Debian 12 or 13 once
# and the host and the image share the two cores
TEST_SELECT ?=

test-serial: setup
	$(PY) -m pytest -q -p no:cacheprovider --durations=25 $(XDIST) $(if $(TEST_SELECT),-m "$(TEST_SELECT)",) tests

# what differs between Debian releases (marker `release`, tests/conftest.py: field,
# surrogate, cli, parallel, the Quick start), then the MPI tier
test-release: setup test-release-serial test-mpi

test-release-serial: setup
	$(PY) -m pytest -q -p no:cacheprovider $(XDIST) -m release tests

# the Debian 13 image's share of CI (scripts/test-container): what differs between releases
# and the slow tests the host leaves to it (marker `image`), then the MPI tier
test-image: setup test-image-serial test-mpi

test-image-serial: setup
	$(PY) -m pytest -q -p no:cacheprovider --durations=25 $(XDIST) -m "release or image" tests

# the fast tier (no subprocess CLI runs, demos, 3D fields or tests over ~1 s): minutes
test-fast: setup
	$(PY) -m pytest -q -p no:cacheprovider $(if $(filter 1,$(TEST_JOBS)),-n 2 --dist loadfile,$(XDIST)) -m "not slow" tests

test-mpi: setup
	mpirun -n 2 $(PY) -m pytest -q -p no:cacheprovider --color=no -m mpi tests

bench: setup
	for b in benchmarks/*.py; do $(PY) $$b || exit 1; done

clean:
	rm -rf $(VENV) $(OUT) build src/*.egg-info
