"""Distinct cases of a block: one steady state per distinct row of case columns, found by
hashing the rows' bits."""

import numpy as np
from numba import njit

from kernels import KERNEL_OPTIONS


@njit(**KERNEL_OPTIONS)
def row_hashes(words):
    """A 64-bit hash of each row of a uint64 matrix (FNV-1a over the words, splitmix64
    finish)."""
    out = np.empty(words.shape[0], dtype=np.uint64)
    for i in range(words.shape[0]):
        h = np.uint64(14695981039346656037)
        for j in range(words.shape[1]):
            h = (h ^ words[i, j]) * np.uint64(1099511628211)
        h ^= h >> np.uint64(30)
        h *= np.uint64(0xBF58476D1CE4E5B9)
        h ^= h >> np.uint64(27)
        h *= np.uint64(0x94D049BB133111EB)
        h ^= h >> np.uint64(31)
        out[i] = h
    return out


@njit(**KERNEL_OPTIONS)
def rows_repeat(words, first, inverse):
    """Is every row of the uint64 matrix bit for bit the row first[inverse[i]]?"""
    for i in range(words.shape[0]):
        j = first[inverse[i]]
        for c in range(words.shape[1]):
            if words[i, c] != words[j, c]:
                return False
    return True


def distinct_rows(keys):
    """(distinct rows, index of each row's distinct row): a 1-D unique on row hashes of the
    bit patterns (-0.0 counts as 0.0), checked row by row, bit for bit (np.unique(axis=0)
    sorts structured rows and cost most of a closed-form block; the same check in numpy,
    with its temporaries, doubled this function's time); a hash
    collision, or NaNs with other bits, falls back to the exact sort."""
    words = np.ascontiguousarray(keys + 0.0).view(np.uint64)
    _, first, inverse = np.unique(row_hashes(words), return_index=True, return_inverse=True)
    if rows_repeat(words, first, inverse.ravel()):
        return keys[first], inverse.ravel()
    cases, inverse = np.unique(keys, axis=0, return_inverse=True)
    return cases, inverse.ravel()
