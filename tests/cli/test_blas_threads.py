"""The command line runs one BLAS thread per process (tengfield._threads, issue #40):
tengfield is parallel by processes, and OpenBLAS threads beside busy processes wait for
each other. A user's own thread variable is left as it is; the library alone never
limits (a notebook keeps its setting)."""
import json
import os
import subprocess
import sys


from tengfield._threads import BLAS_THREAD_VARIABLES, limit_blas_threads

PROBE = """
import json, os, sys
import threadpoolctl
{before}
blas = [i["num_threads"] for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas"]
print(json.dumps({{"threads": blas, "env": os.environ.get("OPENBLAS_NUM_THREADS")}}))
"""


def _probe(before: str, **env) -> dict:
    clean = {k: v for k, v in os.environ.items() if k not in BLAS_THREAD_VARIABLES}
    out = subprocess.run([sys.executable, "-c", PROBE.format(before=before)],
                         env={**clean, **env}, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_the_command_line_limits_blas_to_one_thread_and_the_library_does_not():
    """numpy's BLAS starts as many threads as it likes (a pip wheel's OpenBLAS: one per
    core; Debian 13's numpy on the system's serial OpenBLAS: one), importing tengfield
    changes nothing, the command line's limit makes every BLAS one thread."""
    alone = _probe("import numpy")
    library = _probe("import numpy, tengfield")
    assert library == alone and library["env"] is None
    cli = _probe("import numpy, tengfield.cli\n"
                 "from tengfield._threads import limit_blas_threads\n"
                 "assert limit_blas_threads()")
    assert all(n == 1 for n in cli["threads"]) and cli["env"] == "1"
    assert len(cli["threads"]) == len(alone["threads"])


def test_a_users_own_thread_setting_is_left_as_it_is():
    environ = {"OMP_NUM_THREADS": "2"}
    assert limit_blas_threads(environ) is False
    assert environ == {"OMP_NUM_THREADS": "2"}
    environ = {}                # (this process keeps one BLAS thread from here: harmless)
    before = dict(os.environ)
    assert limit_blas_threads(environ) is True
    assert environ == {"OPENBLAS_NUM_THREADS": "1"}
    assert all(os.environ.get(k) == before.get(k) for k in BLAS_THREAD_VARIABLES)


def test_a_cli_run_starts_its_children_with_one_blas_thread(tmp_path):
    """The figure process and the pools inherit the variable: a command's child reads it."""
    clean = {k: v for k, v in os.environ.items() if k not in BLAS_THREAD_VARIABLES}
    code = ("import os, sys\nfrom tengfield import cli\n"
            "cli._main(['info'])\n"
            "print('CHILD', os.environ.get('OPENBLAS_NUM_THREADS'))")
    out = subprocess.run([sys.executable, "-c", code], env=clean, capture_output=True,
                         text=True, check=True)
    assert "CHILD 1" in out.stdout


def test_a_venv_without_threadpoolctl_still_runs_and_limits_the_children(monkeypatch):
    """A venv made before threadpoolctl was a dependency: no crash, the variable set."""
    monkeypatch.setitem(sys.modules, "threadpoolctl", None)   # import raises ImportError
    environ = {}
    assert limit_blas_threads(environ) is True
    assert environ == {"OPENBLAS_NUM_THREADS": "1"}
