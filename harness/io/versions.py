"""This project's version and the versions of the libraries a result depends on, from the
installed distributions' metadata.  Apart from :mod:`.results` (which records them) so that
``impact-harness --version`` and ``--help`` do not import xarray.
"""
from __future__ import annotations

import platform
from importlib import metadata

PROJECT_DISTRIBUTION = "impact-grazing"
_LIBRARIES = ("fmpy", "numpy", "scipy", "xarray", "netCDF4", "dask", "distributed", "matplotlib")


def project_version() -> str:
    """This project's version (from the installed distribution's metadata)."""
    try:
        return metadata.version(PROJECT_DISTRIBUTION)
    except metadata.PackageNotFoundError:  # pragma: no cover - bare checkout
        return "0+unknown"


def library_versions() -> dict[str, str]:
    """Versions of Python, this project and the libraries a result depends on."""
    out = {"python": platform.python_version()}
    for dist in (PROJECT_DISTRIBUTION, *_LIBRARIES):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = "not installed"
    return out
