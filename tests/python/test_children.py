"""The suite's guard on child processes (conftest.py): a child that panics
(exit 101) or dies of a signal the test did not send fails the test."""

import signal
import subprocess
import sys

import conftest


def test_a_panic_or_an_unsent_signal_is_caught_and_a_stop_on_purpose_is_not():
    def child(code: str):
        return subprocess.Popen([sys.executable, "-c", code])

    panics = child("import sys; sys.exit(101)")
    crashes = child("import os, signal; os.kill(os.getpid(), signal.SIGSEGV)")
    refuses = child("import sys; sys.exit(2)")
    stopped = child("import time; time.sleep(60)")
    stopped.send_signal(signal.SIGTERM)
    mine = [panics, crashes, refuses, stopped]
    for p in mine:
        p.wait()
    assert all(p in conftest._CHILDREN for p in mine), "subprocess.Popen is not the suite's"
    bad = conftest.ended_badly(mine)
    # Forget them, so the guard does not fail this test for the two it caught.
    for p in mine:
        conftest._CHILDREN.remove(p)
    assert len(bad) == 2 and "panicked (exit 101)" in bad[0] and f"killed by signal {signal.SIGSEGV}" in bad[1], bad
