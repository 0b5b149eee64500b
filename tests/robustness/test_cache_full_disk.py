"""A surrogate written to a nearly full filesystem (a 120 kB tmpfs with 8-40 kB free) is
a warning for the cache and a one-line error for ``precompute -o`` (issue #30.14: it
was h5py's "Slist already enabled?" traceback and a segfault). Needs root to mount."""
import os
import subprocess
import sys
import textwrap

import pytest

import plate_model as fx

pytestmark = pytest.mark.skipif(os.geteuid() != 0, reason="mounting a tmpfs needs root")


@pytest.fixture
def nearly_full(tmp_path):
    """A 120 kB tmpfs at tmp_path/full; yields fill(free_kB) that leaves free_kB free."""
    mnt = tmp_path / "full"
    mnt.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=120k", "tmpfs", str(mnt)],
                      capture_output=True).returncode != 0:
        pytest.skip("cannot mount a tmpfs here")

    def fill(free_kb: int):
        for p in mnt.iterdir():
            if p.is_file():
                p.unlink()
        (mnt / "fill").write_bytes(b"\0" * (120 - free_kb) * 1024)
        st = os.statvfs(mnt)
        assert st.f_bavail * st.f_frsize <= free_kb * 1024
        return mnt
    try:
        yield fill
    finally:
        subprocess.run(["umount", str(mnt)], check=False)


@pytest.mark.parametrize("free_kb", [40, 20, 8])
def test_a_full_cache_is_one_warning_and_the_table_is_used(nearly_full, free_kb, cli_env):
    mnt = nearly_full(free_kb)
    code = textwrap.dedent(f"""
        import sys, warnings
        sys.path.insert(0, {os.path.dirname(fx.__file__)!r})
        import plate_model as fx
        from tengfield import surrogate
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            table, outcome = surrogate.obtain_table(fx.scene_with(), cache_dir={str(mnt / 'c')!r},
                                                    solve=fx.CountingSolver())
        full = [w for w in caught if "No space left on device" in str(w.message)]
        print("OUTCOME", outcome.status, outcome.stored, len(full), table.count > 0)
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=cli_env(), timeout=300)
    assert out.returncode == 0, out.stderr[-3000:]
    assert "OUTCOME computed False 1 True" in out.stdout
    assert "Traceback" not in out.stderr
    assert [p.name for p in (mnt / "c").iterdir()] == []    # no temporary left behind


@pytest.mark.slow
@pytest.mark.field
def test_precompute_to_a_full_disk_is_one_line(nearly_full, tmp_path, cli_command, cli_env):
    mnt = nearly_full(20)
    scene = tmp_path / "s.toml"
    scene.write_text("[field]\nmesh_size_mm = 1.0\n")
    out = subprocess.run(cli_command("precompute", scene, "-o", mnt / "s.h5"),
                         capture_output=True, text=True, timeout=900,
                         env=cli_env(TENGFIELD_CACHE_DIR=tmp_path / "cache"))
    assert out.returncode == 1, out.stderr[-3000:]
    errors = [line for line in out.stderr.splitlines() if line.startswith("tengfield: error:")]
    assert errors == [f"tengfield: error: No space left on device: {mnt / 's.h5'}"]
    assert "Traceback" not in out.stderr and "HDF5" not in out.stderr
    assert sorted(p.name for p in mnt.iterdir()) == ["fill"]
