"""Registry entries, one module per mechanism. Importing this package registers them all."""

from sweep.mechanisms import (  # noqa: F401
    crank_rocker,
    linkage_forces,
    rotary_pendulum,
    six_link,
    spring_balancer,
)
