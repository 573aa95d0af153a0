"""Parameter declarations shared by several mechanisms."""

from __future__ import annotations

from sweep.registry import Parameter

#: "impact" is code 0 in every kernel that takes it
SIGMA_IMPACT_CODE = 0.0

POSITIVE = dict(minimum=0.0, min_inclusive=False)


def assembly_branch() -> Parameter:
    """sigma: +1, -1 or the branch that makes the special position an impact."""
    return Parameter("sigma", "1", "assembly branch (sigma): +1, -1, or the impact branch",
                     default="impact", choices={"impact": SIGMA_IMPACT_CODE, 1: 1, -1: -1})


def geometry_tol(what: str) -> Parameter:
    """The relative tolerance of the change-point identities (and of ``what``)."""
    return Parameter("geometry_tol", "1", "relative tolerance of the change-point identities "
                     f"and {what}; such linkages are modelled as exact change points",
                     default=1e-9, minimum=0.0, maximum=1e-3)
