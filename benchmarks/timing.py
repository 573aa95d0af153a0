"""Timing helpers shared by the benchmarks: minimum of repeated runs after a warm-up, and
A/B pairs run in turn so that machine drift hits both alike."""

from __future__ import annotations

import time


def best_time(fn, repeats: int = 5) -> float:
    fn()  # warm-up (compilation, caches)
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def paired_times(a, b, repeats: int = 11) -> tuple[float, float]:
    """Minimum times of a and b run in turn (A B A B ...)."""
    a(), b()
    ta, tb = [], []
    for _ in range(repeats):
        for fn, times in ((a, ta), (b, tb)):
            t = time.perf_counter()
            fn()
            times.append(time.perf_counter() - t)
    return min(ta), min(tb)
