import math

import numpy as np
import pytest

from kernels import crank_rocker as cr
from kernels.status import FLAG_MEANINGS
from sweep import registry

R03 = 0.3
GAMMA03 = 13.0 / 7.0  # (1 + R)/(1 - R) at R = 0.3


def crank_rocker_point(**given):
    """Run the crank-rocker kernel on one point; returns (outputs dict, status meaning)."""
    mech = registry.get("crank_rocker")
    params = np.empty((len(mech.parameters), 1))
    for k, p in enumerate(mech.parameters):
        v = given.get(p.name, p.default)
        params[k, 0] = math.nan if v is None else p.encode(v)
    out, status, _ = mech.run(params, np.array([given.get("geometry_tol", 1e-9)]))
    return dict(zip(cr.OUTPUTS, out[:, 0])), FLAG_MEANINGS[status[0]]


@pytest.fixture
def point():
    return crank_rocker_point
