"""A task for worker processes that imports nothing of scatterbench, so that what it finds
imported there is what the worker itself loaded (tests/test_distributed.py)."""

import sys


def imported(name):
    """Whether module ``name`` is loaded in this process."""
    return name in sys.modules
