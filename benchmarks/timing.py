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


def paired_cpu_times(a, b, repeats: int = 5) -> tuple[float, float]:
    """Median CPU times (this process: user + system) of a and b run in turn (A B B A ...),
    after one warm-up each: CPU time, not wall time, since a loaded machine stretches the
    wall clock of one and not the other."""
    a(), b()
    ta, tb = [], []
    for i in range(repeats):
        for fn, times in ((a, ta), (b, tb)) if i % 2 == 0 else ((b, tb), (a, ta)):
            t = time.process_time()
            fn()
            times.append(time.process_time() - t)
    return sorted(ta)[len(ta) // 2], sorted(tb)[len(tb) // 2]
