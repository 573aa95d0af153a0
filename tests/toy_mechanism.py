"""A toy mechanism, as a new one is added: one declaration and one small kernel in one
module (plus one registry line, which the test that uses it adds)."""

import math
from collections import namedtuple

import numpy as np
from numba import njit

from kernels.block import design_block
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


@njit
def design(i, pr, settings, out, prof):
    speed = abs(pr[P.omega1]) * pr[P.radius] * settings.scale
    out[O.tip_speed] = speed
    out[O.side_used] = pr[P.side]
    return S.ok if math.isfinite(speed) else S.nonfinite


Settings = namedtuple("Settings", ["scale"])
toy_block = design_block(design, "toy_block", globals(), dict(cache=False))


def run(params, method):
    n = params.shape[1]
    out = np.empty((len(O), n))
    status = np.empty(n, dtype=np.int8)
    toy_block(np.ascontiguousarray(params), Settings(scale=float(method.scale)), out, status,
              np.empty((0, n, 0)))
    return out, status, np.empty((0, n, 0))
