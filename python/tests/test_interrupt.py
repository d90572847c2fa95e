"""Ctrl-C during a render raises KeyboardInterrupt promptly and leaves the renderer
usable; renders in a loop do not grow the process."""

import os
import signal
import threading
import time

import numpy as np
import pytest


def test_keyboard_interrupt_during_render(pt):
    before = pt.render(spp=4)
    sent = []

    def interrupt():
        sent.append(time.monotonic())
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(1.0, interrupt)
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        pt.render(spp=1_000_000, progress=False)  # hours on lavapipe
    raised = time.monotonic()
    timer.join()
    assert sent, "the render ended before the signal was sent"
    # Chunks are sized to about half a second: the loop notices at the next boundary.
    assert raised - sent[0] < 3.0
    after = pt.render(spp=4)
    np.testing.assert_array_equal(after.sums, before.sums)


def rss_bytes() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


@pytest.mark.skipif(not os.path.exists("/proc/self/statm"), reason="needs Linux /proc")
def test_rendering_in_a_loop_does_not_grow_the_process(pt):
    for _ in range(10):
        pt.render(spp=1, progress=False)
    start = rss_bytes()
    for _ in range(100):
        img = pt.render(spp=1, progress=False)
        del img
    grown = rss_bytes() - start
    # A 32×24 image is 9 KiB of floats and 18 KiB of sums: leaking either, or any
    # device buffer of the film's size, per render would add megabytes.
    assert grown < 1 << 20, f"the process grew by {grown / 1024:.0f} KiB over 100 renders"
