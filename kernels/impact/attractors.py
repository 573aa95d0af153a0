"""Attractors over several starts: how far apart two section states are, the starting
states of a design (van der Corput's sequence), and whether a sequence reached, or is
contracting onto, a cycle another start found (the rows of ``known``, columns KNOWN)."""

from collections import namedtuple

from numba import njit

from kernels import INLINE_OPTIONS, KERNEL_OPTIONS
from kernels.impact.outcomes import SEQUENCE_CYCLE

#: two section states are one attractor's when they agree to this (relative to max(1, |x|))
ATTRACTOR_TOL = 1e-6
#: the columns of a row of known cycles (``known``): how its sequence ended, its period, 1
#: if it chatters, and from KNOWN.key on its section state
KNOWN = namedtuple("KnownColumns", ["outcome", "period", "chatter", "key"])(0, 1, 2, 3)


@njit(**INLINE_OPTIONS)
def relative_distance(x, y, scale):
    """max_i |x_i - y_i| / max(1, |scale_i|): how far apart two section states are, relative
    where a component is large and absolute where it is small (the period's repeat, a
    known attractor, a capture)."""
    apart = 0.0
    for i in range(len(x)):
        apart = max(apart, abs(x[i] - y[i]) / max(1.0, abs(scale[i])))
    return apart


@njit(**KERNEL_OPTIONS)
def radical_inverse(j, base):
    """The j-th point of van der Corput's sequence in ``base``, in [0, 1): starting states
    that fill their range evenly whatever their number, the same at every N (Halton's
    sequence over bases 2, 3, 5)."""
    x, scale = 0.0, 1.0 / base
    while j > 0:
        x += (j % base) * scale
        j //= base
        scale /= base
    return x


@njit(**KERNEL_OPTIONS)
def known_attractor(known, key):
    """The row of ``known`` (columns KNOWN) whose cycle's section state ``key`` is, to
    ATTRACTOR_TOL; -1 if none. Rows of sequences that ended without a cycle never
    match."""
    for a in range(known.shape[0]):
        if known[a, KNOWN.outcome] != SEQUENCE_CYCLE:
            continue
        state = known[a, KNOWN.key:KNOWN.key + len(key)]
        if not relative_distance(key, state, state) > ATTRACTOR_TOL:
            return a
    return -1


#: a start is captured by a known cycle (captured_by) once its section states of the cycle's
#: phase come within this of the cycle's, each step at most CAPTURE_RATIO of the one before;
#: two cycles whose section states lie within about twice this of each other may then count
#: as one attractor (a start passing that near the other's state looks captured)
CAPTURE_DISTANCE = 1e-4
CAPTURE_RATIO = 0.9


@njit(**KERNEL_OPTIONS)
def captured_by(known, history, count):
    """The row of ``known`` (columns KNOWN) whose cycle the sequence of section states
    ``history`` (rows 0..count-1) is contracting onto: of its last three states p apart (p
    the cycle's period), each is nearer the cycle's state than the one before by at least
    CAPTURE_RATIO, the last within CAPTURE_DISTANCE (relative, as ATTRACTOR_TOL); its own
    steps shrink by CAPTURE_RATIO too, and the cycle's state lies within the reach of their
    geometric tail (ratio/(1 - ratio) times the last): a sequence that converges elsewhere
    stops contracting onto it, its steps vanishing while its distance stays. -1 if none."""
    last = count - 1
    reach = CAPTURE_RATIO / (1.0 - CAPTURE_RATIO)
    for a in range(known.shape[0]):
        if known[a, KNOWN.outcome] != SEQUENCE_CYCLE:
            continue
        p = int(known[a, KNOWN.period])
        if last - 2 * p < 0:
            continue
        cycle = known[a, KNOWN.key:KNOWN.key + history.shape[1]]
        x0, x1, x2 = history[last - 2 * p], history[last - p], history[last]
        d0, d1 = relative_distance(x0, cycle, cycle), relative_distance(x1, cycle, cycle)
        d2 = relative_distance(x2, cycle, cycle)
        s1, s2 = relative_distance(x1, x0, cycle), relative_distance(x2, x1, cycle)
        if (d2 <= CAPTURE_DISTANCE and d2 <= CAPTURE_RATIO * d1 and d1 <= CAPTURE_RATIO * d0
                and s2 <= CAPTURE_RATIO * s1 and d2 <= reach * s2):
            return a
    return -1
