"""``SignalExit`` (``tengfield._mpi``) leaves nothing running once uninstalled: its
watcher thread read the closed pipe's end in a loop and spun a core for the rest of the
process (a test process after every in-process command: CI's host suite ran on one core
less from its middle on)."""
import threading

import pytest

from tengfield._mpi import SignalExit


def _watchers():
    return {t for t in threading.enumerate() if t.name == "tengfield-signal-exit"}


@pytest.mark.parametrize("rank", [1, 3])
def test_an_uninstalled_signal_exit_leaves_no_thread_behind(rank):
    before = _watchers()
    handler = SignalExit(rank=rank).install()
    started = _watchers() - before
    assert len(started) == 1
    handler.uninstall()
    watcher = started.pop()
    watcher.join(timeout=5.0)
    assert not watcher.is_alive()

