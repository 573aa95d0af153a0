"""The rotary pendulum's models and tools, composed into the systems of the integration core
(kernels/impact): the table of systems (table.py), their blocks (systems.py), the closed form
(closed_form.py), the accuracy policy (accuracy.py), the choice of method per case
(dispatch.py) and the distinct cases of a block (distinct.py); kernels/rotary_pendulum.py is
the mechanism's declaration and entry point."""
