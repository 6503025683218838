"""The checks, per seed and per study, and their registry (:mod:`.registry`); the conformance
kit's checks of any model (:mod:`.conformance`, :mod:`.conformance_checks`,
:mod:`.conformance_scatmech`).

Importing the package registers every check of both kinds (a module of it imports the package
first, so both registries are complete whenever one is read); the import order below is the
run order.
"""

# isort: off
from . import registry
from . import seed000, fitting, seed001, seed003, shadowing, stability
from . import conformance, conformance_checks, conformance_scatmech
# isort: on

__all__ = [
    "registry",
    "seed000",
    "fitting",
    "seed001",
    "seed003",
    "shadowing",
    "stability",
    "conformance",
    "conformance_checks",
    "conformance_scatmech",
]
