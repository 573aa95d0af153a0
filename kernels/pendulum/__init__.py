"""The rotary pendulum's models and tools, composed into the systems of the integration core
(kernels/impact); kernels/rotary_pendulum.py is the mechanism's entry point."""
