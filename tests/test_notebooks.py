"""Every notebook of examples/ runs in a real Jupyter kernel (issue 53, docs/python.md):
nbclient executes its cells in order in an ipykernel started from this interpreter
(a kernel spec written for the test: ``sys.executable -m ipykernel_launcher``, this
checkout's ``src`` first on its path), so CI's fresh venv runs the notebook with the
tengfield it tests. A cell that raises fails the test; so does a traceback or a
warning on a cell's stderr. The notebooks are stored without outputs."""
import json
import re
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "examples").glob("*.ipynb"))
KERNEL = "tengfield-test"
#: one cell (the first run builds the field surrogate of the small scene: ~30 s)
CELL_TIMEOUT_S = 600


def test_the_quick_start_notebook_ships_without_outputs():
    import nbformat

    assert ROOT / "examples" / "quickstart.ipynb" in NOTEBOOKS
    for path in NOTEBOOKS:
        nb = nbformat.read(path, as_version=4)
        nbformat.validate(nb)
        for cell in nb.cells:
            if cell.cell_type == "code":
                assert cell.outputs == [] and cell.execution_count is None, path.name


def _kernel_spec(folder: Path, cli_env) -> Path:
    """A Jupyter data folder holding the kernel :data:`KERNEL`: this interpreter, with
    the environment of the CLI's subprocesses (this checkout's src first)."""
    env = cli_env()
    spec = {"argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"],
            "display_name": "tengfield (tests)", "language": "python",
            "env": {k: env[k] for k in ("PYTHONPATH", "OMPI_ALLOW_RUN_AS_ROOT",
                                        "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM",
                                        "OMPI_MCA_btl_tcp_if_include",
                                        "OMPI_MCA_mpi_yield_when_idle",
                                        "TENGFIELD_CACHE_DIR") if k in env}}
    kernel = folder / "kernels" / KERNEL
    kernel.mkdir(parents=True)
    (kernel / "kernel.json").write_text(json.dumps(spec))
    return folder


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_a_notebook_runs_in_a_jupyter_kernel(path, tmp_path, cli_env, monkeypatch):
    import nbformat
    from nbclient import NotebookClient

    monkeypatch.setenv("TENGFIELD_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("JUPYTER_PATH", str(_kernel_spec(tmp_path / "jupyter", cli_env)))
    for name in ("PYVISTA_OFF_SCREEN", "DISPLAY", "MPLBACKEND"):   # as a user's kernel
        monkeypatch.delenv(name, raising=False)
    work = tmp_path / "work"
    work.mkdir()
    nb = nbformat.read(path, as_version=4)
    client = NotebookClient(nb, kernel_name=KERNEL, timeout=CELL_TIMEOUT_S,
                            resources={"metadata": {"path": str(work)}})
    client.execute()            # CellExecutionError if a cell raises
    code = [cell for cell in nb.cells if cell.cell_type == "code"]
    assert all(cell.execution_count for cell in code)
    for cell in code:
        stderr = "".join(o.get("text", "") for o in cell.outputs
                         if o.output_type == "stream" and o.name == "stderr")
        assert not re.search("Traceback|warn|bootstrapping", stderr, re.I), \
            (cell.source, stderr[-3000:])
    figures = sum("image/png" in o.get("data", {}) for cell in code for o in cell.outputs)
    plots = sum(".plot()" in cell.source for cell in code)
    assert figures >= plots, (figures, plots)       # every plot() cell shows its figure
