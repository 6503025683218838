"""The checks, per seed and per study, and their registry (:mod:`.registry`).

Importing the package registers every check; the import order below is the run order.
"""

# isort: off
from . import registry
from . import seed000, fitting, seed001, seed003, shadowing, stability
# isort: on

__all__ = ["registry", "seed000", "fitting", "seed001", "seed003", "shadowing", "stability"]
