"""Status codes written by every kernel, one per grid point.

The atlas stores them as CF ``flag_values``/``flag_meanings``; each mechanism declares the
statuses its kernel emits (``kernels.declaration``), and a kernel writes them by name
(``S.not_assemblable``). The codes are stable across mechanisms and versions: append new
ones, never renumber. Codes 6 and 7 (``chatter``, ``grazing``) were reserved and never
emitted: chatter is a regime of the pendulum, not a failed point, and a grazing contact is
located, not flagged; they are retired, not reused.
"""

CODES = {
    "ok": 0,
    "not_assemblable": 1,  # the links cannot close over a full crank turn
    "no_real_synthesis": 2,  # the synthesis equations have no real, positive solution
    "wrong_branch": 3,  # the requested assembly branch is not the impact branch (|Rk| > 1)
    "special_position": 4,  # peaks are taken outside a window around a special position
    "escape": 5,  # the pendulum goes over the top: no periodic impact regime
    "max_steps": 8,  # the integration or the impact iteration hit its limit
    "step_underflow": 9,  # the step size fell below round-off
    "resonance": 10,  # a harmonic sits on a resonance: the steady state does not exist
    "truncation": 11,  # the harmonic count is too small for the requested tolerance
    "nonfinite": 12,  # a computed value came out non-finite where the model says it exists
    "degenerate": 13,  # B on D at the special position; a rotor thrown back by the impact
    "no_impact": 14,  # gamma <= 1, or the striker never reaches the tool
    "second_special_position": 15,  # a second change point on the turn
    "no_special_position": 16,  # a general four-bar that is not a change-point linkage
    "not_periodic": 17,  # the impact sequence did not settle into a cycle (quasi-periodic)
    "separatrix": 18,  # the steady impact speed is the escape threshold: no period exists
    "stalls": 19,  # the crank stops (the motor cannot carry the machine through a turn)
    "reverses": 20,  # the blow throws the crank backwards: no one-blow-per-turn regime
    "singular_inertia": 21,  # the reduced inertia vanishes on the cycle (no crank inertia)
    "too_slow": 22,  # a revolution takes too long to be a working machine
    "no_convergence": 23,  # no periodic steady state within the revolutions allowed
    "gains_energy": 24,  # the blow's law creates energy (the kinematic law): no steady state
    "unreachable_speed": 25,  # the motor cannot hold the crank speed asked of it
}
#: the meaning of each code
MEANINGS = {code: name for name, code in CODES.items()}
