"""Ctrl-C during a render raises KeyboardInterrupt promptly and leaves the renderer
usable; renders in a loop do not grow the process."""

import gc
import os
import signal
import threading
import time

import numpy as np
import pytest


@pytest.fixture
def sigint_raises():
    """Python's own SIGINT handler for the test's duration. A process started in the
    background by a shell without job control inherits SIGINT ignored, and Python then
    installs no handler: Ctrl-C could not reach it, and the test would fail for that."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def test_keyboard_interrupt_during_render(pt, sigint_raises):
    before = pt.render(spp=4)
    sent = []

    def interrupt():
        sent.append(time.monotonic())
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(1.0, interrupt)
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        # Bounded, so that a renderer that ignores Ctrl-C fails the test instead of hanging it.
        pt.render(seconds=30, progress=False)
    raised = time.monotonic()
    timer.join()
    assert sent, "the render ended before the signal was sent"
    # Chunks are sized to about half a second: the loop notices at the next boundary.
    assert raised - sent[0] < 3.0
    after = pt.render(spp=4)
    np.testing.assert_array_equal(after.sums, before.sums)


def heap_bytes() -> int:
    """Bytes the C heap has handed out and not taken back (glibc's mallinfo2): unlike
    the resident size, it grows with a leak even while freed memory is being reused."""
    import ctypes

    class MallInfo2(ctypes.Structure):
        _fields_ = [(n, ctypes.c_size_t) for n in (
            "arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks",
            "uordblks", "fordblks", "keepcost")]

    libc = ctypes.CDLL("libc.so.6")
    libc.mallinfo2.restype = MallInfo2
    m = libc.mallinfo2()
    return m.uordblks + m.hblkhd


def has_mallinfo2() -> bool:
    try:
        heap_bytes()
        return True
    except (OSError, AttributeError):
        return False


@pytest.mark.skipif(not has_mallinfo2(), reason="needs glibc's mallinfo2")
def test_rendering_in_a_loop_does_not_grow_the_process(pt):
    for _ in range(10):
        pt.render(spp=1, progress=False)
    gc.collect()
    heap, device = heap_bytes(), pt._native._device_memory()
    for _ in range(100):
        img = pt.render(spp=1, progress=False)
        del img
    gc.collect()
    # No device allocation outlives a render (buffers, staging, read-backs).
    assert pt._native._device_memory() == device
    # A 32×24 render returns 27 KiB of floats and sums: leaking them, or anything of
    # the film's size, per render would add megabytes. (Without leaks the heap grows by
    # well under 100 KiB, the validation layer's own records.)
    grown = heap_bytes() - heap
    assert grown < 512 << 10, f"the heap grew by {grown / 1024:.0f} KiB over 100 renders"
