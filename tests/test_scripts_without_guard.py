"""Python as researchers run it (issue 53, docs/python.md): a script without an
``if __name__ == "__main__":`` guard and ``python -`` from a heredoc run the worker
pools (``tf.map``, ``tf.sweep``, every start method of :mod:`tengfield._pool`) to the
same result as the serial loop, with a clean stderr; a worker that cannot start ends
the pool with one error line instead of a wait."""
import subprocess
import textwrap

import pytest

pytestmark = pytest.mark.slow

#: a subprocess that re-ran its script in the workers used to print thousands of
#: tracebacks and never end: the timeout turns that into a failure, not a hang
TIMEOUT_S = 300

SMALL = ('{"duration_s": 0.3, "settle_periods": 2, "sample_rate_hz": 5000}')


def _run(python, env, tmp_path, code, *, stdin: bool):
    """``code`` as a script file ``python script.py`` (no guard) or as ``python -``."""
    code = textwrap.dedent(code)
    if stdin:
        argv, given = [python, "-"], code
    else:
        (tmp_path / "script.py").write_text(code)
        argv, given = [python, "script.py"], None
    return subprocess.run(argv, input=given, cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=TIMEOUT_S)


def _assert_clean(done):
    assert done.returncode == 0, done.stderr[-3000:]
    for bad in ("Traceback", "Error", "bootstrapping"):
        assert bad not in done.stderr, done.stderr[-3000:]


@pytest.mark.parametrize("stdin", [False, True], ids=["script", "stdin"])
def test_every_start_method_runs_tengfields_pool_from_an_unguarded_script(
        python, cli_env, tmp_path, stdin):
    done = _run(python, cli_env(), tmp_path, """
        import sys
        from tengfield._pool import process_pool
        print("main ran", file=sys.stdout)
        for method in ("fork", "forkserver", "spawn"):
            with process_pool(2, method) as pool:
                print(method, list(pool.map(abs, [-1, -2, -3, -4])))
        """, stdin=stdin)
    _assert_clean(done)
    lines = done.stdout.splitlines()
    assert lines.count("main ran") == 1      # no worker re-ran the script
    for method in ("fork", "forkserver", "spawn"):
        assert f"{method} [1, 2, 3, 4]" in lines


@pytest.mark.parametrize("stdin", [False, True], ids=["script", "stdin"])
def test_map_and_sweep_with_jobs_equal_the_serial_loop_without_a_guard(
        python, cli_env, tmp_path, stdin):
    done = _run(python, cli_env(), tmp_path, f"""
        import tengfield as tf
        scene = tf.default_scene().with_values(run={SMALL})
        serial = tf.map(scene, frequency_hz="20:40:3", amplitude_mm="0.5:2:3", jobs=1)
        pooled = tf.map(scene, frequency_hz="20:40:3", amplitude_mm="0.5:2:3", jobs=2)
        print("map", serial.summary["regimes"] == pooled.summary["regimes"],
              sum(serial.summary["regimes"].values()))
        one = tf.sweep(scene, frequency_hz=[20, 30], amplitude_mm=[1.0, 1.5], jobs=1)
        two = tf.sweep(scene, frequency_hz=[20, 30], amplitude_mm=[1.0, 1.5], jobs=2)
        print("sweep", len(two), [r["Q_sc_pp_C"] for r in one] == [r["Q_sc_pp_C"] for r in two],
              all(r["Q_sc_pp_C"] > 0 for r in two))
        """, stdin=stdin)
    _assert_clean(done)
    assert "map True 9" in done.stdout.splitlines()
    assert "sweep 4 True True" in done.stdout.splitlines()


def test_a_worker_that_cannot_start_ends_the_pool_with_one_error_line(
        python, cli_env, tmp_path):
    # every worker exits in its initializer; the tasks (1 MB each) fill the pipe to
    # the workers, on which Python 3.11's executor used to wait for ever
    done = _run(python, cli_env(), tmp_path, """
        import sys
        from tengfield._pool import PoolError, process_pool
        try:
            with process_pool(2, "forkserver", initializer=sys.exit) as pool:
                print(sum(pool.map(len, [bytes(1 << 20)] * 40)))
        except PoolError as exc:
            print("PoolError:", exc)
        """, stdin=False)
    assert done.returncode == 0, done.stderr[-3000:]
    (line,) = done.stdout.splitlines()
    assert line.startswith("PoolError: a worker process of the 2-worker pool")
    assert "--jobs 1" in line
