"""The cost of field solves before the work (issue #40): the estimate from the mesh rule,
``[field] max_memory_gb`` refused in one line before meshing, the (z, r) table's scene
keys, a solver allocation failure in one line (issue #43 item 4), and the thin
spherical shell's mesh kept local (its gap rule no longer refines the whole domain)."""
import numpy as np
import pytest
from mpi4py import MPI

from tengfield.errors import FieldError, SceneError
from tengfield.scene import Scene, default_scene

field = pytest.mark.field

#: the thin spherical shell of issue #40 / #43 item 4: stroke 0.31 mm
THIN_SHELL = {"shape": "spherical-shell", "cavity_diameter_mm": 9.209, "shell_thickness_mm": 2.0,
              "electrode_band_mm": 2.0, "ball_diameter_mm": 8.899, "wall_permittivity": 3.0,
              "surface_charge_uC_per_m2": -50.0}


def thin_shell(**field_keys):
    return Scene.from_dict({"device": THIN_SHELL, "field": field_keys})


# -- the estimate ---------------------------------------------------------------------
def test_the_estimate_grows_as_the_mesh_is_refined_and_with_the_error_estimate():
    from tengfield.field.cost import solve_cost

    scene = default_scene()
    coarse = solve_cost(scene, position=1.5e-3, estimate_error=False)
    fine = solve_cost(scene.with_values(field={"mesh_size_mm": 0.25}), position=1.5e-3,
                      estimate_error=False)
    assert 2.0 < fine.dofs / coarse.dofs < 4.5   # graded: between h^-1 and h^-2 in 2D
    assert coarse.check_dofs == 0.0
    both = solve_cost(scene, position=1.5e-3)
    assert both.check_dofs > 2.0 * both.dofs and both.memory_bytes > coarse.memory_bytes
    three = solve_cost(scene, method="3d", estimate_error=False)
    assert three.dofs > 20 * coarse.dofs                 # 3D at the same mesh size


@field
@pytest.mark.slow
@pytest.mark.parametrize("scene", [default_scene(), thin_shell()], ids=["tube", "thin-shell"])
def test_the_estimate_is_within_a_factor_two_of_the_mesh(scene):
    from tengfield.field import solve_position
    from tengfield.field.cost import solve_cost

    z = 0.5 * scene.device.stroke
    solved = solve_position(scene, z, comm=MPI.COMM_SELF, estimate_error=False)
    estimated = solve_cost(scene, position=z, estimate_error=False)
    assert 0.5 < estimated.dofs / solved.dofs < 2.0


def test_max_memory_gb_refuses_in_one_line_before_meshing(monkeypatch):
    from tengfield.field import solve_position
    from tengfield.field import geometry_axisymmetric

    def no_meshing(*args, **kwargs):
        raise AssertionError("meshed")
    monkeypatch.setattr(geometry_axisymmetric, "build_model", no_meshing)
    scene = default_scene().with_values(field={"max_memory_gb": 0.01})
    with pytest.raises(FieldError) as refused:
        solve_position(scene, 1.5e-3, comm=MPI.COMM_SELF)
    text = str(refused.value)
    assert "\n" not in text and "max_memory_gb = 0.01" in text and "allowed <= 0.01 GB" in text


def test_max_memory_gb_by_default_is_a_share_of_the_machine():
    from tengfield.field.cost import MACHINE_SHARE, machine_memory_bytes, memory_limit_bytes

    assert default_scene().field.max_memory_gb == 0.0
    assert memory_limit_bytes(default_scene()) == pytest.approx(
        MACHINE_SHARE * machine_memory_bytes())
    assert memory_limit_bytes(default_scene().with_values(field={"max_memory_gb": 3})) == 3e9


@pytest.mark.parametrize("key, value", [("max_memory_gb", -1), ("radial_degree", 3),
                                        ("radial_mesh_size_mm", 0), ("radial_tolerance", 1)])
def test_the_new_field_keys_are_checked(key, value):
    with pytest.raises(SceneError, match=key):
        default_scene().with_values(field={key: value})


def test_the_new_keys_leave_the_field_hash_alone():
    scene = default_scene()
    for values in ({"max_memory_gb": 2}, {"radial_mesh_size_mm": 1.0, "radial_degree": 1,
                                          "radial_tolerance": 0.05}):
        assert scene.with_values(field=values).field_hash() == scene.field_hash()


def test_the_zr_table_settings_come_from_the_scene():
    from tengfield.pipeline import _radial_settings

    scene = default_scene().with_values(field={"radial_mesh_size_mm": 2.5, "radial_degree": 1,
                                               "radial_tolerance": 0.03})
    assert _radial_settings(scene) == {"mesh_size_mm": pytest.approx(2.5), "degree": 1,
                                       "tolerance": pytest.approx(0.03)}
    assert _radial_settings(default_scene()) == {"mesh_size_mm": pytest.approx(1.5),
                                                 "degree": 2, "tolerance": pytest.approx(1e-2)}


def laplacian_2d(n: int):
    """The 5-point Laplacian of an n x n grid (CSR, n² unknowns, symmetric positive
    definite)."""
    import scipy.sparse as sp

    one = sp.diags([-1, 2, -1], [-1, 0, 1], shape=(n, n))
    return (sp.kron(sp.identity(n), one) + sp.kron(one, sp.identity(n))).tocsr()


@field
def test_a_solver_allocation_failure_is_one_line():
    from tengfield.field import _dolfinx as dx

    n = 120
    A = laplacian_2d(n)
    M = dx.matrix_from_csr(MPI.COMM_SELF, A.shape, A.indptr, A.indices, A.data)
    prefix = dx.unique_prefix("starved")
    with pytest.raises(FieldError) as failed:   # MUMPS allowed 1 MB of workspace
        dx.create_ksp(MPI.COMM_SELF, M, prefix=prefix, symmetric=True,
                      options={"pc_factor_mat_solver_type": "mumps",
                               "mat_mumps_icntl_23": 1})
    text = str(failed.value)
    assert "\n" not in text and "ran out of memory" in text and f"{n * n} unknowns" in text
    assert "MUMPS LDLT" in text
    assert not any(key.startswith(prefix) for key in dx.PETSc.Options().getAll())


@field
def test_the_serial_symmetric_solver_is_cholmod_and_matches_mumps_and_fails_in_one_line():
    """One process, a symmetric operator: CHOLMOD (SuiteSparse, in Debian 12's and 13's
    PETSc) solves a 2D Laplacian as MUMPS LDLT does (to 1e-12), the refactorisation of
    new values too; an indefinite matrix is one line naming the solver."""
    import scipy.sparse as sp

    from tengfield.field import _dolfinx as dx

    assert dx.direct_solver(MPI.COMM_SELF, symmetric=True) == "cholmod"
    assert dx.direct_solver(MPI.COMM_SELF, symmetric=False) == "mumps"
    n = 40
    A = laplacian_2d(n)
    rng = np.random.default_rng(7)
    b = rng.standard_normal(n * n)
    solutions = {}
    for package in ("cholmod", "mumps"):
        M = dx.matrix_from_csr(MPI.COMM_SELF, A.shape, A.indptr, A.indices, A.data)
        prefix = dx.unique_prefix(package)
        ksp = dx.create_ksp(MPI.COMM_SELF, M, prefix=prefix, symmetric=True,
                            options={"pc_factor_mat_solver_type": package})
        assert ksp.getPC().getFactorSolverType() == package
        first = dx.solve(ksp, dx.vector(MPI.COMM_SELF, b)).array.copy()
        M.scale(2.0)                                   # new values, the same pattern
        dx.refactor(ksp, M, symmetric=True)
        second = dx.solve(ksp, dx.vector(MPI.COMM_SELF, b)).array.copy()
        solutions[package] = (first, second)
        ksp.destroy()
        dx.clear_options(prefix)
    scale = np.abs(solutions["mumps"][0]).max()
    np.testing.assert_allclose(solutions["cholmod"][0], solutions["mumps"][0], rtol=0,
                               atol=1e-12 * scale)
    np.testing.assert_allclose(solutions["cholmod"][1], 0.5 * solutions["cholmod"][0],
                               rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(A @ solutions["cholmod"][0], b, atol=1e-10)
    indefinite = A - 4.0 * sp.identity(n * n, format="csr")
    M = dx.matrix_from_csr(MPI.COMM_SELF, A.shape, indefinite.indptr, indefinite.indices,
                           indefinite.data)
    prefix = dx.unique_prefix("indefinite")
    with pytest.raises(FieldError) as failed:
        dx.create_ksp(MPI.COMM_SELF, M, prefix=prefix, symmetric=True)
    text = str(failed.value)
    assert "\n" not in text and "CHOLMOD" in text and f"{n * n} unknowns" in text
    assert not any(key.startswith(prefix) for key in dx.PETSc.Options().getAll())


@field
def test_the_serial_factorisation_is_cholmods_simplicial_one():
    """CHOLMOD is told to factor simplicially (``mat_cholmod_factor simplicial``): on the
    axisymmetric solver's 2D P2 operators (13k-23k unknowns) its set-up and two solves
    took 24-40 ms against 34-58 ms for the supernodal factorisation CHOLMOD picked by
    itself (its own default, ``Common.supernodal`` 1: AUTO); issue #40."""
    import re

    from tengfield.field import _dolfinx as dx

    n = 30
    A = laplacian_2d(n)
    M = dx.matrix_from_csr(MPI.COMM_SELF, A.shape, A.indptr, A.indices, A.data)
    prefix = dx.unique_prefix("simplicial")
    ksp = dx.create_ksp(MPI.COMM_SELF, M, prefix=prefix, symmetric=True)
    try:
        text = dx.factor_description(ksp)
    finally:
        ksp.destroy()
        dx.clear_options(prefix)
    assert "package used to perform factorization: cholmod" in text, text
    setting = re.search(r"Common\.supernodal\s+(\d+)", text)
    assert setting is not None and setting.group(1) == "0", text   # 0: CHOLMOD_SIMPLICIAL


@field
def test_the_factorisations_run_on_openblas():
    """The BLAS and LAPACK that PETSc (CHOLMOD, MUMPS) loads are OpenBLAS's
    (scripts/install-system.sh installs libopenblas0-serial; Debian's alternatives rank
    it above the reference BLAS, whose dense kernels made the design's factorisations
    ~8 % slower end to end)."""
    from tengfield.field import _dolfinx  # noqa: F401 - loads PETSc and its BLAS

    with open("/proc/self/maps") as maps:
        mapped = {line.split()[-1] for line in maps if "/" in line}
    blas = sorted(p for p in mapped if p.rsplit("/", 1)[-1].startswith(("libblas.so",
                                                                          "liblapack.so")))
    assert blas and all("openblas" in p for p in blas), blas


# -- the thin shell's mesh ------------------------------------------------------------
@field
@pytest.mark.slow
def test_the_thin_shells_mesh_stays_local_to_its_gaps():
    """A nearly concentric ball (stroke 0.31 mm): the gap rule refined a disk of ~15 mm
    around each gap (72k dofs at mid-stroke, ~600k at the smallest gap); meshed in the gap
    only, a gap of 19 um costs about what mid-stroke does, and mid-stroke keeps its
    accuracy and the cell's mirror symmetry."""
    from tengfield.field import solve_position

    scene = thin_shell()
    g = 0.02 * scene.device.stroke
    mid = solve_position(scene, 0.5 * scene.device.stroke, comm=MPI.COMM_SELF)
    near = solve_position(scene, 3 * g, comm=MPI.COMM_SELF, estimate_error=False)
    assert mid.dofs < 20_000 and near.dofs < 2 * mid.dofs
    assert mid.relative_error_estimate < 1e-3
    # the ball at mid-stroke of a symmetric cell: q_lower = q_upper, C_ll = C_uu
    assert mid.induced_charge[0] == pytest.approx(mid.induced_charge[1], rel=1e-3)
    assert np.isclose(mid.capacitance[0, 0], mid.capacitance[1, 1], rtol=1e-3)


def test_the_field_command_refuses_past_max_memory_gb_before_writing(run_cli, tmp_path):
    out = tmp_path / "field"
    done = run_cli("field", "--position-mm", "1.5", "--set", "field.max_memory_gb=0.05",
                   "--no-plots", "-o", out)
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "max_memory_gb = 0.05" in lines[0] and "GB" in lines[0]
    assert not out.exists()


@pytest.mark.parametrize("terminal", [False, True], ids=["piped", "terminal"])
def test_progress_shows_under_mpirun_on_a_terminal(python, terminal):
    """Under mpirun a rank's stderr is a pipe to the launcher even when the launcher's
    is a terminal: the field phases' progress (the (z, r) table's minutes of 3D solves)
    showed nothing there. Now it shows when mpirun's stderr is a terminal, and only then."""
    import os
    import pty
    import shutil
    import subprocess

    from conftest import cli_environment

    mpirun = shutil.which("mpirun")
    if mpirun is None:
        pytest.skip("no mpirun")
    env = cli_environment()
    env.pop("TENGFIELD_QUIET", None)
    code = ("import sys; from tengfield._console import progress_shown; "
            "print('shown' if progress_shown(True) else 'silent')")
    master = slave = None
    if terminal:
        master, slave = pty.openpty()
    try:
        done = subprocess.run([mpirun, "-n", "1", python, "-c", code], stdout=subprocess.PIPE,
                              stderr=slave if terminal else subprocess.PIPE, env=env,
                              timeout=120, text=True)
    finally:
        for fd in (slave, master):
            if fd is not None:
                os.close(fd)
    assert done.stdout.strip().splitlines()[-1] == ("shown" if terminal else "silent")


@field
@pytest.mark.slow
def test_precompute_on_a_terminal_says_the_solves_and_their_cost_first(cli_command, tmp_path):
    """`tengfield precompute` on a terminal: the number of solves and the estimate in one
    line before the progress bar (read through a pseudo-terminal)."""
    import os
    import pty
    import select
    import subprocess

    from conftest import cli_environment

    scene = tmp_path / "coarse.toml"
    scene.write_text("[field]\nmesh_size_mm = 1.0\ntolerance = 0.01\n")
    master, slave = pty.openpty()
    env = cli_environment(TENGFIELD_CACHE_DIR=str(tmp_path / "cache"))
    env.pop("TENGFIELD_QUIET", None)
    proc = subprocess.Popen(cli_command("precompute", scene), stdout=subprocess.DEVNULL,
                            stderr=slave, env=env)
    os.close(slave)
    seen = b""
    while True:
        ready, _, _ = select.select([master], [], [], 1.0)
        if ready:
            try:
                chunk = os.read(master, 4096)
            except OSError:
                break
            if not chunk:
                break
            seen += chunk
        elif proc.poll() is not None:
            break
    proc.wait(timeout=600)
    os.close(master)
    text = seen.decode(errors="replace").replace("\r", "\n")
    assert proc.returncode == 0
    lines = [line for line in text.splitlines() if line.strip()]
    first = lines[0]
    assert first.startswith("tengfield: field solves (at least; 17 positions, mirror symmetry): 9,")
    assert "dofs each" in first and "GB" in first and "estimated before meshing" in first
    assert any(line.startswith("field solves:") for line in lines[1:])


# -- a 3D tolerance out of reach, said before the work (issue #55) ---------------------
def _three_d(**field_keys):
    return default_scene().with_values(field={"method": "3d", **field_keys})


def test_the_expected_3d_error_is_the_measured_one():
    """The tube's measured error against dofs (docs/field3d.md, "Graded meshes"): the
    fitted line passes through the measured points it was fitted on and near the third."""
    from tengfield.field.cost import dofs_for_error_3d, expected_error_3d

    uniform, graded = _three_d(), _three_d(mesh_grading="graded")
    assert expected_error_3d(uniform, 1_126_226) == pytest.approx(3.2e-3)
    assert expected_error_3d(uniform, 442_583) == pytest.approx(4.5e-3, rel=0.02)
    assert expected_error_3d(uniform, 173_923) == pytest.approx(6.9e-3, rel=0.2)
    assert expected_error_3d(graded, 237_690) == pytest.approx(5.7e-3, rel=0.02)
    assert expected_error_3d(graded, 103_766) == pytest.approx(1.5e-2, rel=0.2)
    for scene in (uniform, graded):               # the inverse
        for error in (1e-3, 3e-3, 1e-2):
            assert expected_error_3d(scene, dofs_for_error_3d(scene, error)) == \
                pytest.approx(error)
    shell = Scene.from_dict({"device": THIN_SHELL, "field": {"method": "3d"}})
    assert expected_error_3d(shell, 1e6) is None              # not measured: not claimed
    assert expected_error_3d(_three_d(degree=1), 1e6) is None


def test_a_graded_3d_mesh_is_estimated_with_its_fewer_dofs():
    from tengfield.field.cost import GRADED_DOFS_SHARE, solve_cost

    uniform = solve_cost(_three_d(), method="3d", estimate_error=False)
    graded = solve_cost(_three_d(mesh_grading="graded"), method="3d", estimate_error=False)
    assert graded.dofs == pytest.approx(GRADED_DOFS_SHARE * uniform.dofs)
    assert 0.45e6 < graded.dofs < 0.65e6                      # measured 548k at 0.5 mm
    shell = Scene.from_dict({"device": THIN_SHELL, "field": {"mesh_grading": "graded"}})
    plain = Scene.from_dict({"device": THIN_SHELL})
    assert solve_cost(shell, method="3d").dofs == solve_cost(plain, method="3d").dofs


def test_a_3d_tolerance_out_of_reach_within_the_memory_is_said_before_the_work(monkeypatch):
    """The default 3D solve (uniform, tolerance 1e-3) ends near 3.2e-3; reaching 1e-3 the
    uniform way needs ~20M dofs: one warning line before any meshing, naming the graded
    mesh that would fit. Graded within the memory: nothing; a small limit: the graded
    solve is told too; a tolerance in reach, the axisymmetric solve: nothing."""
    import warnings

    from tengfield.field import solve_position
    from tengfield.field.cost import solve_cost, tolerance_problem

    limit = {"max_memory_gb": 16.0}
    line = tolerance_problem(_three_d(**limit), solve_cost(_three_d(**limit), method="3d"))
    assert line is not None and "\n" not in line
    assert line.startswith("[field] tolerance = 0.001: a 3D solve of this scene is expected "
                           "to end near 0.0032")
    assert "more than [field] max_memory_gb allows (16 GB)" in line
    assert "mesh_grading = 'graded' is expected to reach it" in line
    graded = _three_d(mesh_grading="graded", **limit)
    assert tolerance_problem(graded, solve_cost(graded, method="3d")) is None
    small = _three_d(mesh_grading="graded", max_memory_gb=1.0)
    told = tolerance_problem(small, solve_cost(small, method="3d"))
    assert told is not None and "allows (1 GB)" in told and "'uniform' is expected" not in told
    loose = _three_d(tolerance=1e-2, **limit)
    assert tolerance_problem(loose, solve_cost(loose, method="3d")) is None
    assert tolerance_problem(default_scene(), solve_cost(default_scene())) is None

    class NoSolve:
        def solve_scene(self, *args, **kwargs):
            raise AssertionError("solved")
    from tengfield.field import cells
    monkeypatch.setattr(cells, "cell_of", lambda scene: NoSolve())
    with warnings.catch_warnings(record=True) as caught, pytest.raises(AssertionError,
                                                                    match="solved"):
        warnings.simplefilter("always")
        solve_position(_three_d(**limit), 1.5e-3, comm=MPI.COMM_SELF)
    assert [str(w.message) for w in caught] == [line]     # said before the cell's solve
