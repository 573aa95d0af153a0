"""The pendulum systems, declared once: each model on each tool, and what it supports.

Everything that depends on which (model, tool) a case is derives from ``SYSTEMS``: the
compiled entry points and their dispatch (kernels/pendulum/systems.py), the choice of
method (kernels/pendulum/dispatch.py), the spec's rules (kernels/rotary_pendulum.py) and
the list in docs/impact_core.md. Models and tools are named here and coded by these names;
their functions live in models.py (a ``Model`` per name) and tools.py (a contact factory
per tool name).

Adding a system is a row here; a new tool is also its contact factory (tools.py), a new
model its ``Model`` (models.py) and its parameters from a case (systems.py).
"""

from collections import namedtuple

from kernels.impact.runge_kutta import METHOD_DOP853, METHOD_RK4
from kernels.pendulum.models import MODEL_PAPER, MODEL_RIGID, MODEL_ROTOR

#: the models, by name: the codes of the spec's ``model``
MODELS = {"paper": MODEL_PAPER, "rigid": MODEL_RIGID, "rotor": MODEL_ROTOR}
#: the tools, by name: the codes of the spec's ``tool``
TOOL_ROTOR_STOP, TOOL_LAB_WINDOW = 0, 1
TOOLS = {"rotor_stop": TOOL_ROTOR_STOP, "lab_window": TOOL_LAB_WINDOW}
#: tools whose flights end where they started (a stop on the rotor): pi over the flight
#: time is then the free oscillation's frequency coefficient
RETURNING_TOOLS = ("rotor_stop",)

#: a system: its model and tool (names), and what it supports:
#: ``closed_form``: the whole steady state in closed form (no flight integrated);
#: ``exact_flow``: flights stepped exactly by the model's closed-form flow (METHOD_EXACT);
#: ``slide``: the tool has a face the striker can ride (a slide after a plastic contact);
#: ``tangent``: the multipliers need the tangent integrated through the cycle (elsewhere
#: they are known in closed form);
#: ``affine``: the section map is affine in closed form, so the sequence jumps to its
#: fixed point from the start and two sections (Aitken)
PendulumSystem = namedtuple("PendulumSystem", ["model", "tool", "closed_form", "exact_flow",
                                               "slide", "tangent", "affine"])

SYSTEMS = tuple(PendulumSystem(*row) for row in (
    # model    tool          closed_form exact_flow slide  tangent affine
    ("paper", "rotor_stop", True, False, False, False, True),
    ("rigid", "rotor_stop", True, False, False, False, True),
    ("rotor", "rotor_stop", False, False, False, True, False),
    ("paper", "lab_window", False, False, True, True, False),
    ("rigid", "lab_window", False, True, True, True, False),
    ("rotor", "lab_window", False, False, True, True, False),
))
#: each system by its (model code, tool code)
BY_CODES = {(MODELS[s.model], TOOLS[s.tool]): s for s in SYSTEMS}


#: the names of the methods an entry point may have compiled in beside DOPRI5
METHOD_NAMES = {METHOD_DOP853: "dop853", METHOD_RK4: "rk4"}


def entry_name(system: PendulumSystem, tangent: bool = False, methods: tuple = (),
               two_stage: bool = False, several_starts: bool = False) -> str:
    """The name of a system's compiled entry point:
    ``<model>_on_<tool>[_tangent][_dop853|_rk4][_two_stage][_starts]`` (with the tangent;
    with DOP853 or RK4 compiled in beside DOPRI5, ``methods``; with auto's second stage;
    for several starts per case)."""
    return (f"{system.model}_on_{system.tool}" + ("_tangent" if tangent else "")
            + "".join("_" + METHOD_NAMES[m] for m in methods)
            + ("_two_stage" if two_stage else "")
            + ("_starts" if several_starts else ""))


def with_closed_form(given_models, given_tools) -> bool:
    """Does every (model, tool) pair of these names have a closed form (the whole steady
    state, or exact flights)?"""
    return all(s.closed_form or s.exact_flow for s in SYSTEMS
               if s.model in given_models and s.tool in given_tools)
