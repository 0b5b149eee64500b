"""A bit flip in a dataset's header of a cached surrogate is refused before the data is
read (issue #30.7: a flipped dimension claimed 9 GB of a 76 kB file; the run reached
24 GB). The check runs in a child limited to 1.5 GB of address space, so a regression
fails with MemoryError instead of exhausting the machine."""
import struct
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from tengfield import surrogate

import plate_model as fx


def _flipped_file(tmp_path, scene):
    table = surrogate.precompute(scene, solve=fx.plate_model_solve, solve_comm=object())
    path = surrogate.write_table(tmp_path / "s.h5", table)
    data = bytearray(path.read_bytes())
    n = table.count
    at = data.find(struct.pack("<QQQ", n, 2, 2))   # capacitance_F's dataspace (n, 2, 2)
    assert at > 0
    data[at + 11] ^= 0x02                            # the middle dimension: 2 + 2**25
    path.write_bytes(bytes(data))
    return path, n


def test_a_flipped_dimension_is_refused_before_reading(tmp_path, plate_default_scene, cli_env):
    path, n = _flipped_file(tmp_path, plate_default_scene)
    code = textwrap.dedent(f"""
        import resource
        resource.setrlimit(resource.RLIMIT_AS, (1_500_000_000, 1_500_000_000))
        from tengfield import surrogate
        try:
            surrogate.read_table({str(path)!r})
        except surrogate.SurrogateError as exc:
            print("REFUSED", exc)
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=cli_env(), timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "REFUSED" in out.stdout and "header is damaged (not read)" in out.stdout
    # HDF5 1.10 (Debian 12) opens the header and tengfield measures it against the bytes
    # stored; HDF5 1.14 (Debian 13) refuses the dimension beyond its maximum itself
    assert f"claims shape ({n}, 33554434, 2)" in out.stdout or "maxdim" in out.stdout


def test_a_flipped_cache_file_is_recomputed_with_one_warning(tmp_path, plate_default_scene,
                                                            cli_env):
    """The cache reader warns once and recomputes (in a memory-limited child, too)."""
    scene = plate_default_scene
    cache = tmp_path / "cache"
    first, _ = surrogate.obtain_table(scene, cache_dir=cache, solve=fx.CountingSolver())
    path = surrogate.cache_path(scene, cache)
    flipped, _ = _flipped_file(tmp_path, scene)
    path.write_bytes(flipped.read_bytes())
    np.save(tmp_path / "first.npy", first.capacitance)
    code = textwrap.dedent(f"""
        import resource, sys, warnings
        resource.setrlimit(resource.RLIMIT_AS, (3_000_000_000, 3_000_000_000))
        sys.path.insert(0, {str(fx.__file__.rsplit("/", 1)[0])!r})
        import numpy as np
        import plate_model as fx
        from tengfield import surrogate
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            table, outcome = surrogate.obtain_table(fx.scene_with(), cache_dir={str(cache)!r},
                                                    solve=fx.CountingSolver())
        damaged = [w for w in caught if "header is damaged" in str(w.message)]
        same = np.array_equal(table.capacitance, np.load({str(tmp_path / "first.npy")!r}))
        print("OUTCOME", outcome.status, len(damaged), same)
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=cli_env(), timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "OUTCOME recomputed 1 True" in out.stdout
