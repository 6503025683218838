"""``scatterbench models``: every model with its declared parameters."""

from __future__ import annotations

from scatterbench import models
from scatterbench.validation.testing import format_contributed

__all__ = ["register"]


def _cmd_models(args) -> int:

    print(models.list_models())
    print(format_contributed())
    return 0


def register(sub):
    p = sub.add_parser("models", help="list the models and their declared parameters")
    p.set_defaults(func=_cmd_models)
