"""The stop flag behind every SIGTERM handler: it wakes a waiter, keeps the first reason, and
cannot deadlock the main thread when a signal lands inside a wait."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from tslam.stopflag import StopFlag

ROOT = Path(__file__).resolve().parent.parent

# The daemon's loop, reduced: the main thread waits in short slices (the daemon's cycle at a
# time scale of 20 is 5 ms) while signals keep arriving. With threading.Event in place of the
# flag this hangs or crashes within a few hundred signals: the handler's set() wants the lock
# that the interrupted wait() holds.
CHILD = """
import signal, sys
from tslam.stopflag import StopFlag, stop_on_signals
flag = StopFlag()
bye = []
signal.signal(signal.SIGTERM, lambda *_: bye.append(1))
with stop_on_signals(flag.set, (signal.SIGUSR1,)):
    print("ready", flush=True)
    while not bye:
        flag.wait(1e-4)
print(flag.reason, flush=True)
"""


def test_signals_landing_inside_waits_never_deadlock_the_waiter():
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True, env=env,
    )  # fmt: skip
    try:
        assert child.stdout.readline().strip() == "ready"
        for _ in range(300):
            child.send_signal(signal.SIGUSR1)
            time.sleep(0.001)
        child.send_signal(signal.SIGTERM)
        out, err = child.communicate(timeout=20)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait(10)
    assert child.returncode == 0, err
    assert out.strip() == "SIGUSR1"


def test_set_from_another_thread_wakes_a_waiter_and_keeps_the_first_reason():
    flag = StopFlag()
    try:
        assert flag.wait(0.01) is False and not flag.is_set()
        threading.Timer(0.05, flag.set, args=("first",)).start()
        assert flag.wait(30.0) is True
        flag.set("second")
        assert flag.reason == "first"
        assert flag.wait(0) is True
    finally:
        flag.close()
    flag.set("after close")  # a late signal after shutdown is harmless
    assert flag.reason == "first"
