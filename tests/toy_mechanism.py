"""A toy mechanism, as a new one is added: one declaration and one small kernel in one
module (plus one registry line, which the test that uses it adds)."""

import math

import numpy as np
from numba import njit

from kernels.declaration import POSITIVE, Mechanism, Output, Quantity

DECLARATION = Mechanism(
    name="toy",
    title="Toy: the tip speed of a crank",
    summary="closed form: v = |omega1| r scale",
    references="none: a test fixture",
    parameters=(
        Quantity("radius", "m", "crank radius (r)", "r", default=0.1, **POSITIVE),
        Quantity("omega1", "rad s-1", "crank angular velocity (omega1)", "ω1", default=10.0,
                 nonzero=True),
        Quantity("side", "1", "which side of the crank is measured", default="near",
                 choices={"near": 0, "far": 1}),
    ),
    outputs=(
        Output("tip_speed", "m s-1", "speed of the crank tip", "v"),
        Output("side_used", "1", "the side measured", flags={"near": 0, "far": 1}),
    ),
    status=("ok", "nonfinite"),
    method=(Quantity("scale", "1", "a factor on the speed", default=1.0, **POSITIVE),),
)
P = DECLARATION.parameter_index
O = DECLARATION.output_index
S = DECLARATION.status_codes


@njit(cache=False)
def _block(params, scale, out, status):
    for i in range(params.shape[1]):
        speed = abs(params[P.omega1, i]) * params[P.radius, i] * scale
        out[O.tip_speed, i] = speed
        out[O.side_used, i] = params[P.side, i]
        status[i] = S.ok if math.isfinite(speed) else S.nonfinite


def run(params, method):
    out = np.empty((len(O), params.shape[1]))
    status = np.empty(params.shape[1], dtype=np.int8)
    _block(params, method.scale, out, status)
    return out, status, np.empty((0, params.shape[1], 0))
