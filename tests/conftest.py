"""Fixtures shared by the whole suite: the interpreter, the CLI in a subprocess, the
default scene of the analytic plate model (``tests/plate_model.py``)."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

# a pytest-xdist worker ignores SIGINT, and an ignored signal is inherited across exec:
# the Ctrl-C tests' children would never see theirs. Python's own handler here is reset
# to the default in every child (docs/development.md)
import signal  # noqa: E402

if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

# pyvista before dolfinx in every test process (VTK's text rendering aborts the process
# in the reverse order: an in-process field.png, e.g. ``PositionResult.write``, drawn
# by a pytest-xdist worker whose earlier tests had imported dolfinx; docs/field.md)
try:
    import pyvista  # noqa: F401,E402
except ImportError:   # the fast tier without the plotting stack
    pass

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"


def cli_environment(**extra) -> dict:
    """The environment of a CLI subprocess: this checkout's ``src`` first, MPI allowed as
    root, and nothing set up for the CLI (no PYVISTA_OFF_SCREEN, no DISPLAY: it must cope);
    ``extra`` overrides (e.g. ``TENGFIELD_CACHE_DIR=...``)."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYVISTA_OFF_SCREEN", "DISPLAY", "VTK_DEFAULT_OPENGL_WINDOW")}
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(SRC), env.get("PYTHONPATH")) if p)
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    env.setdefault("OMPI_MCA_btl_tcp_if_include", "lo")    # one machine (Makefile)
    env.setdefault("OMPI_MCA_mpi_yield_when_idle", "1")    # share the cores (Makefile)
    env.update({k: str(v) for k, v in extra.items()})
    return env



#: the folders whose tests depend on what differs between Debian releases (dolfinx 0.5 /
#: 0.9, HDF5, numpy 1 / 2, Open MPI 4 / 5, pyvista/VTK): their fast tests are marked
#: ``release`` here and run again in the Debian 13 image by ``make test-release`` (the
#: host's ``make test`` runs every test); so are the files below (the Quick start, the
#: warm-up) and the slow tests of :data:`RELEASE_SLOW` (one per code path that differs)
RELEASE_FOLDERS = ("field", "surrogate", "cli", "parallel")
RELEASE_FILES = ("test_readme_quickstart.py", "test_warmup.py",
                 # Python as researchers run it (docs/python.md): multiprocessing, VTK's
                 # window and the Jupyter stack differ between Python 3.11 and 3.13
                 "test_scripts_without_guard.py", "test_notebooks.py")
RELEASE_SLOW = (
    "field/test_field_3d.py::test_offset_direction_does_not_matter_in_a_round_tube",  # 3D
    "field/test_spherical_shell_3d.py::test_the_3d_solve_on_the_axis_equals_the_axisymmetric_one",
    "field/test_field_cli.py::test_field_command_3d_on_two_ranks_equals_serial",  # + pyvista
    "cli/test_io_hdf5.py::test_the_papers_15_minute_record_runs_in_hdf5_with_bounded_memory",
    "parallel/test_mpi_interrupt.py::test_an_interrupted_design_ends_every_rank_cleanly",
    "parallel/test_mpi_interrupt.py::test_an_interrupted_uncertainty_study_leaves_no_new_directory",
)


#: the slow tests that CI runs in the Debian 13 image instead of on the host (a file, or a
#: ``file::test``): ``.ci/run`` gives the host's ``make test`` ``TEST_SELECT="not image"``
#: and the image runs ``make test-image`` (``-m "release or image"``), so every test still
#: runs on Debian 12 or 13 in each CI run and the two halves share the machine's two cores
#: (tests/test_ci_split.py holds both expressions to that). ``make test`` by hand runs
#: everything. Release-dependent tests in these files stay on both.
IMAGE_SHARE = (
    "test_demos.py",                                # the demos, serial and under mpirun
    # the spherical shell, the second cell: its slow 3D and (z, r) work
    "field/test_spherical_shell_3d.py",
    "field/test_shell_scene.py",
    "surrogate/test_surrogate_zr.py",
    "dynamics/motion3d/test_shell_cli.py",
    "pipeline/test_shell_studies.py",
    # every ```python block of the docs as scripts (minutes: README.md alone 110 s)
    "test_docs_python.py",
    # stop 58: the host's half had grown to 36 min against the image's ~28 (~210 s moved)
    "electrical/test_stream_memory.py",             # 4x longer runs, memory measured
    "source/test_contact_studies.py",               # contact charge in the studies, mpirun
    "design/test_design_mpi.py",                    # designs with real solves, mpirun
    # 2026-12-06: the single-electrode cell's end-to-end runs off the axis and in the shell
    "field/test_single_electrode_3d.py::test_run_takes_the_single_electrode_off_the_axis_with_figures",
    "field/test_single_electrode_shell.py::test_a_run_of_the_single_electrode_shell_moves_less_than_the_pairs",
    "field/test_single_electrode_3d.py::test_a_honeycomb_cell_of_one_electrode_moves_less_than_its_pair",
)


def _relative(item) -> Path:
    return Path(str(item.fspath)).resolve().relative_to(ROOT / "tests")


def _in_image_share(item) -> bool:
    relative = _relative(item).as_posix()
    return relative in IMAGE_SHARE or f"{relative}::{item.originalname}" in IMAGE_SHARE


def _is_release_dependent(item) -> bool:
    relative = _relative(item)
    if relative.name in RELEASE_FILES:
        return True
    if f"{relative.as_posix()}::{item.originalname}" in RELEASE_SLOW:
        return True
    in_folder = relative.parts[0] in RELEASE_FOLDERS or item.get_closest_marker("field")
    return bool(in_folder) and item.get_closest_marker("slow") is None


@pytest.hookimpl(tryfirst=True)   # before ``-m`` selects by marker
def pytest_collection_modifyitems(config, items):
    """Every fast test in :data:`RELEASE_FOLDERS` or marked ``field``, every test in
    :data:`RELEASE_FILES` and those of :data:`RELEASE_SLOW` are marked ``release`` too; the
    other tests of :data:`IMAGE_SHARE` ``image``. ``mpi`` tests need ``mpirun -n 2``: outside mpirun they are
    deselected, so that a ``-m`` given on the command line (``-m "not slow"``, the fast
    tier) replacing the ``-m 'not mpi'`` of pyproject's addopts still leaves them out of a
    serial run."""
    for item in items:
        if _is_release_dependent(item):
            item.add_marker(pytest.mark.release)
        elif _in_image_share(item):
            item.add_marker(pytest.mark.image)
    if os.environ.get("OMPI_COMM_WORLD_SIZE") or os.environ.get("PMI_SIZE"):
        return
    mpi = [item for item in items if item.get_closest_marker("mpi")]
    if mpi:
        config.hook.pytest_deselected(items=mpi)
        items[:] = [item for item in items if not item.get_closest_marker("mpi")]

@pytest.fixture(scope="session")
def python() -> str:
    """The interpreter running the tests (the venv's python under ``make test``)."""
    return sys.executable


@pytest.fixture(scope="session")
def cli_env():
    """``cli_env(**extra)`` -> dict: see :func:`cli_environment`."""
    return cli_environment


@pytest.fixture(scope="session")
def cli_command(python):
    """``cli_command(*args)``: the argv that runs ``tengfield args...``."""
    return lambda *args: [python, "-m", "tengfield.cli", *map(str, args)]


@pytest.fixture(scope="session")
def run_cli(cli_command):
    """``run_cli(*args, cwd=None, env=None, timeout=900)`` -> CompletedProcess (text,
    captured) of ``python -m tengfield.cli args...``; ``env`` defaults to ``cli_env()``."""
    def run(*args, cwd=None, env=None, timeout=900):
        return subprocess.run(cli_command(*args), cwd=cwd, env=env or cli_environment(),
                              capture_output=True, text=True, timeout=timeout)
    return run


@pytest.fixture(scope="session")
def plate_default_scene():
    """The default scene (no overrides), as ``plate_model.scene_with()`` gives it."""
    import plate_model
    return plate_model.scene_with()


@pytest.fixture(scope="session")
def plate_solve():
    """The analytic stand-in for ``solve_position`` (``plate_model.plate_model_solve``)."""
    import plate_model
    return plate_model.plate_model_solve
