"""Registry entries, one module per mechanism. Importing this package registers them all."""

from sweep.mechanisms import crank_rocker, linkage_forces, six_link, spring_balancer  # noqa: F401
