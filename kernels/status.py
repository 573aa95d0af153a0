"""Status codes written by every kernel, one per grid point.

The atlas stores them as CF ``flag_values``/``flag_meanings``; the numbers are stable across
mechanisms and versions (append new ones, never renumber). Module-level ints are compile-time
constants for numba.
"""

OK = 0
NOT_ASSEMBLABLE = 1  # the links cannot close over a full crank turn
NO_REAL_SYNTHESIS = 2  # the synthesis equations have no real, positive solution
WRONG_BRANCH = 3  # the requested assembly branch is not the impact branch (|Rk| > 1)
SPECIAL_POSITION = 4
ESCAPE = 5
CHATTER = 6
GRAZING = 7
MAX_STEPS = 8
STEP_UNDERFLOW = 9
RESONANCE = 10
TRUNCATION = 11
NONFINITE = 12  # a computed value came out non-finite where the model says it exists
DEGENERATE = 13  # B coincides with D at the special position (linkages.md H9)
NO_IMPACT = 14  # gamma <= 1: the rocker does not reverse at the special position
SECOND_SPECIAL_POSITION = 15  # a second change point on the turn (linkages.md H10)
NO_SPECIAL_POSITION = 16  # a general four-bar that is not a change-point linkage

FLAG_MEANINGS = (
    "ok",
    "not_assemblable",
    "no_real_synthesis",
    "wrong_branch",
    "special_position",
    "escape",
    "chatter",
    "grazing",
    "max_steps",
    "step_underflow",
    "resonance",
    "truncation",
    "nonfinite",
    "degenerate",
    "no_impact",
    "second_special_position",
    "no_special_position",
)
