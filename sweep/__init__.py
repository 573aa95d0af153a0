"""impact-sweep: batch parameter sweeps of impact mechanisms into CF-annotated netCDF atlases.

The Python API (the same functions the ``sweep`` command line calls)::

    import sweep

    atlas = sweep.run(sweep.example("crank_rocker"))          # an xarray.Dataset
    designs = sweep.query(atlas, 'status == "ok"', sort="impact_speed", descending=True)
    sweep.chart(atlas, x="R", y="largest_link", color="impact_speed").savefig("v.png")

``Sweep`` (``from_toml``, ``from_dict``), ``run``, ``open_atlas``, ``query``, ``chart``,
``profile``, ``explore``, ``sheet``, ``sensitivity``, ``tolerance``, ``design_spec``, ``robust``, ``lines``, ``boundaries``, ``pareto``, ``with_requirements``, ``info``, ``parameters``,
``example``, ``examples``, ``warmup`` and ``UserError`` are documented in ``sweep.api``. ``import sweep``
is light: each name is imported on first use, and heavy libraries (numba, xarray, dask,
matplotlib) by the functions that need them.

The import names ``sweep`` and ``kernels`` are generic (PyPI has unrelated packages with the
same names); install impact-sweep in its own environment.
"""

__all__ = ["Sweep", "UserError", "boundaries", "chart", "decode", "example", "examples",
           "explore", "info", "open_atlas", "open_boundaries", "parameters", "pareto", "profile",
           "query", "robust", "run", "sensitivity", "sheet", "tolerance", "design_spec",
           "lines", "warmup", "with_requirements"]


def __getattr__(name: str):
    # PEP 562: the API's names on first use, so that the command line's start-up (and
    # `import sweep`) does not pay for numba and the spec's validation it may not need
    if name == "__version__":
        from sweep.metadata import package_version

        return package_version()
    if name in __all__:
        from sweep import api

        return getattr(api, name)
    raise AttributeError(f"module 'sweep' has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + __all__)
