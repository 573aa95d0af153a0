"""Non-dominated designs: the Pareto front of n designs in k objectives, all minimised.

A design a dominates b when a is no worse in every objective and better in at least one;
the front is the designs no other dominates. Equal designs do not dominate each other, so
ties stay on the front together. Values must be finite (the caller leaves out designs
without a value).

In lexicographic order only an earlier design can dominate a later one, and an earlier
design that is no worse in every objective but the first dominates it unless the two are
equal. So:

- two objectives: one sort and one sweep keeping the best second objective so far,
  O(n log n) (Kung, Luccio and Preparata 1975);
- three: the same sweep asks whether an earlier design has f2 and f3 both no worse; a
  Fenwick tree over the ranks of f2 holding the least f3 answers in O(log n), O(n log n)
  in all;
- more: sort-filter-skyline (Chomicki et al. 2003): each design compared with the front
  found so far, the last one that dominated first, O(n log n + n F k) at worst for a front
  of F designs.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from kernels import INLINE_OPTIONS, INNER_OPTIONS, KERNEL_OPTIONS


@njit(**INNER_OPTIONS)
def lexicographic_order(values):
    """Indices that sort the rows of values (n, k) by the first column, ties by the
    second, and so on: stable sorts from the last column to the first."""
    n, k = values.shape
    order = np.arange(n)
    for j in range(k - 1, -1, -1):
        column = values[order, j]
        order = order[np.argsort(column, kind="mergesort")]
    return order


@njit(**INNER_OPTIONS)
def _front_of_two(values, order, keep):
    """The sweep in (f1, f2) order: within a run of equal f1 the first f2 is the run's
    best; it (and its equals) is on the front when it beats every earlier run's best."""
    n = order.shape[0]
    best = np.inf
    i = 0
    while i < n:
        first = values[order[i], 0]
        lead = values[order[i], 1]
        j = i
        while j < n and values[order[j], 0] == first:
            j += 1
        if lead < best:
            for m in range(i, j):
                if values[order[m], 1] == lead:
                    keep[order[m]] = True
            best = lead
        i = j


@njit(**INNER_OPTIONS)
def _front_of_three(values, order, keep):
    """The sweep in (f1, f2, f3) order, one run of equal designs at a time: the run is
    dominated when an earlier design has f2 <= and f3 <= its own (prefix minimum of f3 over
    the ranks of f2 up to its rank, in a Fenwick tree), else it joins the tree."""
    n = order.shape[0]
    by_second = np.argsort(values[:, 1], kind="mergesort")
    rank = np.empty(n, np.int64)  # 1-based; equal f2 share their highest rank
    i = 0
    while i < n:
        j = i
        while j + 1 < n and values[by_second[j + 1], 1] == values[by_second[i], 1]:
            j += 1
        for m in range(i, j + 1):
            rank[by_second[m]] = j + 1
        i = j + 1
    least = np.full(n + 1, np.inf)
    i = 0
    while i < n:
        p = order[i]
        j = i
        while j + 1 < n and values[order[j + 1], 0] == values[p, 0] \
                and values[order[j + 1], 1] == values[p, 1] \
                and values[order[j + 1], 2] == values[p, 2]:
            j += 1
        best = np.inf
        r = rank[p]
        while r > 0:
            best = min(best, least[r])
            r -= r & -r
        if not best <= values[p, 2]:
            for m in range(i, j + 1):
                keep[order[m]] = True
            r = rank[p]
            while r <= n:
                least[r] = min(least[r], values[p, 2])
                r += r & -r
        i = j + 1


@njit(**INLINE_OPTIONS)
def _dominates(values, a, b):
    better = False
    for j in range(values.shape[1]):
        if values[a, j] > values[b, j]:
            return False
        if values[a, j] < values[b, j]:
            better = True
    return better


@njit(**INNER_OPTIONS)
def _front_of_many(values, order, keep):
    front = np.empty(order.shape[0], np.int64)
    size = 0
    for i in range(order.shape[0]):
        p = order[i]
        dominated = False
        for m in range(size):
            if _dominates(values, front[m], p):
                dominated = True
                # move it to the window's head: a design that dominates one tends to
                # dominate the next (they are near in lexicographic order)
                q = front[m]
                for back in range(m, 0, -1):
                    front[back] = front[back - 1]
                front[0] = q
                break
        if not dominated:
            front[size] = p
            size += 1
            keep[p] = True


@njit(**KERNEL_OPTIONS)
def non_dominated(values):
    """A boolean mask of the designs on the front of values (n designs, k objectives, all
    minimised, finite)."""
    n, k = values.shape
    keep = np.zeros(n, np.bool_)
    if n == 0:
        return keep
    order = lexicographic_order(values)
    if k == 1:
        best = values[order[0], 0]
        for i in range(n):
            keep[i] = values[i, 0] == best
    elif k == 2:
        _front_of_two(values, order, keep)
    elif k == 3:
        _front_of_three(values, order, keep)
    else:
        _front_of_many(values, order, keep)
    return keep
