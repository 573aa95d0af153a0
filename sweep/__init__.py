"""impact-sweep: batch parameter sweeps of impact mechanisms into CF-annotated netCDF atlases.

The import names ``sweep`` and ``kernels`` are generic (PyPI has unrelated packages with the
same names); install impact-sweep in its own environment.
"""

__version__ = "0.1.0"
