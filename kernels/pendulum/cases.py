"""The layouts the pendulum's blocks share: a case's columns (what a steady state depends on;
omega1 and l2 only rescale it) and the slots of a case's result row."""

from collections import namedtuple

CASE_COLUMNS = ("model", "k", "xi", "kappa", "R", "tool", "tool_window",
                "rotor_inertia_ratio", "motor_slope", "idle_speed")
C = namedtuple("CaseColumns", CASE_COLUMNS)(*range(len(CASE_COLUMNS)))

#: a case's result, in omega1 units: how its sequence ended (outcomes.SEQUENCE_*), the
#: cycle's period and whether it chatters, amplitude [rad], frequency ratio n, impact
#: interval [rotor rad], striker normal speed at impact [omega1 l_contact], impacts to
#: converge, peak |psi''| [omega1^2], R_crit, steps, rejected steps, events, mean rotor speed
#: [omega1], method used, estimated relative error of the cycle's values (auto); on
#: request, the cycle's margins: slowest over fastest impact speed, distance of an impact
#: from the blade's edge [rad], the leading multiplier's modulus and argument [rad], and
#: over several starts the distinct attractors and the share reaching the one from rest; the
#: integrated cycle's section state (its tool's key, the pre-impact state of its canonical
#: section: on the rotor stop phi1' and psi' [omega1])
ROW_SLOTS = ("outcome", "period", "chatter", "amplitude", "frequency", "interval", "speed",
             "impacts", "acceleration", "restitution_critical", "steps", "rejected", "events",
             "rotor_speed", "method", "error", "speed_ratio", "edge", "modulus", "angle",
             "attractors", "basin", "section_0", "section_1", "section_2")
ROW = namedtuple("RowSlots", ROW_SLOTS)(*range(len(ROW_SLOTS)))
N_ROW = len(ROW_SLOTS)
