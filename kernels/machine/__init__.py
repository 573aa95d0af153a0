"""The crank-driven impact machine's numerics, one idea per file (its entry point is
kernels/impact_machine.py): ``declaration`` (parameters, outputs, statuses), ``data`` (the
machine's named record), ``dynamics`` (J(phi1), Q(phi1), the motor), ``blow`` (the node and
the generalised Newton impact), ``revolution`` (one revolution on the integration core),
``cycle`` (the periodic steady state), ``flywheel`` (sizing for a speed fluctuation),
``forces`` (joint reactions over the dynamic cycle). Each returns its own outcome codes;
the entry point maps them to statuses."""
