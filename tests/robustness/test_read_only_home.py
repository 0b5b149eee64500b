"""#30.20: a read-only $HOME (no writable ~/.cache) is one line naming the form compiler's
(dolfinx/FFCx JIT) cache and XDG_CACHE_HOME, exit 2 (it was `tengfield: error: Read-only
file system: .../.cache`, exit 1); with XDG_CACHE_HOME pointing elsewhere the solve runs.
A read-only filesystem is a real read-only tmpfs (root ignores chmod); needs root."""
from __future__ import annotations

import os
import subprocess

import pytest

pytestmark = [pytest.mark.slow, pytest.mark.field,
              pytest.mark.skipif(os.geteuid() != 0, reason="mounting a tmpfs needs root")]


@pytest.fixture
def read_only(tmp_path):
    """``read_only(*dirs)``: a tmpfs at tmp_path/ro holding ``dirs``, mounted read-only."""
    mnt = tmp_path / "ro"
    mnt.mkdir()
    mounted = []

    def make(*dirs):
        if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", str(mnt)],
                          capture_output=True).returncode != 0:
            pytest.skip("cannot mount a tmpfs here")
        mounted.append(mnt)
        for d in dirs:
            (mnt / d).mkdir(parents=True)
        subprocess.run(["mount", "-o", "remount,ro", str(mnt)], check=True)
        with pytest.raises(OSError):
            (mnt / "probe").write_text("x")
        return mnt

    yield make
    for m in mounted:
        subprocess.run(["umount", str(m)], check=False)


def _env(cli_env, **extra):
    env = cli_env(MPLBACKEND="Agg", **extra)
    env.pop("XDG_CACHE_HOME", None)
    env.update({k: str(v) for k, v in extra.items()})
    return env


def _one_line_error(done, cache):
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert lines[0].startswith(f"tengfield: error: the form compiler's cache (dolfinx/FFCx "
                               f"JIT) {cache} cannot be written (Read-only file system")
    assert "XDG_CACHE_HOME" in lines[0]


def test_a_read_only_home_names_the_compiler_cache(read_only, tmp_path, run_cli, cli_env):
    home = read_only()
    out = tmp_path / "out"
    done = run_cli("field", "--position-mm", "1", "--no-plots", "-o", out,
                   env=_env(cli_env, HOME=home))
    _one_line_error(done, home / ".cache" / "fenics")
    # the advice works: the compiler's cache elsewhere, $HOME still read-only
    done = run_cli("field", "--position-mm", "1", "--no-plots", "-o", out,
                   env=_env(cli_env, HOME=home, XDG_CACHE_HOME=tmp_path / "cache"))
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "cache" / "fenics").is_dir() and (out / "field.json").exists()


def test_an_existing_read_only_compiler_cache_is_named_too(read_only, tmp_path, run_cli,
                                                           cli_env):
    """The cache directory exists (so it can be created) but a new module cannot be
    written into it: the compiler's own error, named the same way."""
    cache = read_only("fenics")
    done = run_cli("field", "--position-mm", "1", "--no-plots", "-o", tmp_path / "out",
                   env=_env(cli_env, XDG_CACHE_HOME=cache))
    _one_line_error(done, cache / "fenics")
