"""Helpers shared by test files (imported by name: ``from helpers import mpi_env``); a
test file imports helpers from here or from the analytic stand-ins (``plate_model``,
``zr_model``), never from another test file."""
from __future__ import annotations

import math
import os
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


def mpi_env():
    return dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                OMPI_MCA_rmaps_base_oversubscribe="1", MPLBACKEND="Agg",
                PYTHONPATH=os.pathsep.join(p for p in (str(ROOT / "src"),
                                                       os.environ.get("PYTHONPATH")) if p))


def needs_mpirun():
    if shutil.which("mpirun") is None:
        pytest.skip("mpirun not installed")


def same_rows(a: list[dict], b: list[dict]) -> bool:
    """Row lists equal exactly (None and NaN compare equal to themselves)."""
    if len(a) != len(b):
        return False
    for x, y in zip(a, b):
        if x.keys() != y.keys():
            return False
        for k in x:
            u, v = x[k], y[k]
            if isinstance(u, float) and isinstance(v, float) and math.isnan(u) and math.isnan(v):
                continue
            if u != v:
                return False
    return True


def assert_png(path):
    """``path`` is a non-empty PNG that decodes to an image with content."""
    from PIL import Image

    assert path.stat().st_size > 0, path
    with Image.open(path) as image:
        assert image.format == "PNG"
        image.load()
        pixels = np.asarray(image.convert("L"))
    assert pixels.shape[0] > 100 and pixels.shape[1] > 100
    assert pixels.std() > 1.0, f"{path} is blank"


def quick_start_commands() -> list[str]:
    """The command lines of README's Quick start block (comments dropped)."""
    text = (ROOT / "README.md").read_text()
    block = re.search(r"## Quick start\s*```bash\n(.*?)```", text, re.S).group(1)
    return [line.split("#")[0].strip() for line in block.splitlines() if line.split("#")[0].strip()]


def quick_start_script(lines: list[str]) -> str:
    """``lines`` as one bash script that stops at the first failing line."""
    return "set -e\n" + "\n".join(lines) + "\n"
