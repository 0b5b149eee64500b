"""``python -m tengfield._warmup`` (run by ``make setup`` and the Dockerfile) leaves
numba's on-disk cache filled, and the next process uses it: the kernels of a
``tengfield run`` load from the cache instead of compiling again."""
import subprocess

import pytest

pytestmark = pytest.mark.slow  # compiles every kernel once in a fresh cache (~40 s)

# after the warm-up, in a new process: the default scene's dynamics (what
# `tengfield run` and `tengfield dynamics` do first), the 3D ball and a
# harvest, with numba's cache log on
NEXT_PROCESS = """
import time
import numpy as np
from tengfield import harvest
from tengfield.dynamics import simulate
from tengfield.scene import default_scene, parse_scene
t0 = time.perf_counter()
simulate(default_scene())
simulate(parse_scene('[contact]\\nmodel = "3d"\\n[run]\\nduration_s = 0.1\\nsettle_periods = 1\\n'))
t = np.linspace(0.0, 0.05, 200)
harvest.harvest(t, 1e-9 * np.sin(t), 4e-13 + 0 * t, storage_capacitance=1e-6)
print(f"SECONDS {time.perf_counter() - t0:.3f}")
"""


@pytest.fixture(scope="module")
def warm_cache(tmp_path_factory, python, cli_env):
    """A fresh NUMBA_CACHE_DIR after one warm-up, and the warm-up's output."""
    cache = tmp_path_factory.mktemp("numba-cache")
    env = cli_env(NUMBA_CACHE_DIR=cache)
    done = subprocess.run([python, "-m", "tengfield._warmup"], env=env, capture_output=True,
                          text=True, timeout=900)
    assert done.returncode == 0, done.stdout + done.stderr
    return cache, env, done.stdout


def test_warmup_fills_the_cache(warm_cache):
    cache, _, out = warm_cache
    from tengfield import _warmup

    kernels = _warmup.kernels()
    assert len(kernels) >= 40, [k.__name__ for k in kernels]
    # every kernel but the one nothing calls has an index and compiled code in `cache`
    assert f"{len(kernels) - 1} of {len(kernels)} numba kernels in the cache" in out, out
    index_files = list(cache.rglob("*.nbi"))
    data_files = list(cache.rglob("*.nbc"))
    assert len(index_files) == len(kernels) - 1, sorted(p.name for p in index_files)
    assert len(data_files) >= len(index_files)
    for name in ("run_impact_map", "sample_segments", "run_3d", "_harvest_kernel",
                 "sample_many", "spline_terminal"):
        assert any(f".{name}-" in p.name for p in index_files), name


def test_next_process_loads_instead_of_compiling(warm_cache, python):
    cache, env, _ = warm_cache
    before = sorted((p.name, p.stat().st_size) for p in cache.rglob("*"))
    done = subprocess.run([python, "-c", NEXT_PROCESS], env={**env, "NUMBA_DEBUG_CACHE": "1"},
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    log = done.stdout + done.stderr
    loaded = [line for line in log.splitlines() if "data loaded" in line]
    saved = [line for line in log.splitlines() if "data saved" in line]
    assert not saved, "compiled again instead of loading:\n" + "\n".join(saved)
    for name in ("run_impact_map", "run_3d", "_harvest_kernel"):
        assert any(f".{name}-" in line for line in loaded), (name, log[-3000:])
    # nothing was added to or rewritten in the cache
    assert sorted((p.name, p.stat().st_size) for p in cache.rglob("*")) == before
    # loading takes well under a second where compiling took tens of seconds
    seconds = float(next(line.split()[1] for line in log.splitlines()
                         if line.startswith("SECONDS")))
    assert seconds < 10.0, seconds
