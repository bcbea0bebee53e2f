# Long calls release the GIL: another Python thread runs while fvm works.
import threading
import time

import numpy as np

import fvm


def test_focus_lets_other_threads_run():
    stack = np.random.default_rng(1).integers(0, 255, (20, 400, 400), dtype=np.uint8)  # ~0.3 s of focus variation
    span = {}

    def work():
        start = time.perf_counter()
        fvm.focus(stack, np.arange(20) * 0.002)
        span["t"] = (start, time.perf_counter())

    worker = threading.Thread(target=work)
    stamps = []
    worker.start()
    while worker.is_alive():
        stamps.append(time.perf_counter())  # this thread's progress
    worker.join()
    t0, t1 = span["t"]
    inside = [s for s in stamps if t0 < s < t1]
    # Holding the GIL, the call would stop this thread for all of its ~0.3 s (less the few ms of argument and
    # result conversion); released, this thread's longest pause is the scheduler's, milliseconds. Half the call
    # separates the two with room for a loaded machine.
    assert t1 - t0 > 0.05
    assert np.max(np.diff([t0, *inside, t1])) < 0.5 * (t1 - t0)
