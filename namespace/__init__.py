"""scatterbench: a validation and benchmark harness for polarized light-scattering models.

One import namespace over the repository's three folders (pyproject.toml's package-dir maps
them; this file is the package's own ``__init__``):

* :mod:`scatterbench.models`: the physics, every BRDF/BTDF model (``models/``);
* :mod:`scatterbench.validation`: checks, numerics, fitting, studies, reports, the command
  line and the conformance kit (``validation/``);
* :mod:`scatterbench.references`: published numbers and peer reference values with their
  provenance, and their loaders (``references/``).

``from scatterbench import models, validation`` imports them; nothing is imported here, so
``import scatterbench`` stays cheap and a command loads only what it uses.
"""

from importlib import metadata

try:
    __version__ = metadata.version("scatterbench")
except metadata.PackageNotFoundError:  # pragma: no cover - run from an uninstalled tree
    __version__ = "unknown"

__all__ = ["__version__"]
