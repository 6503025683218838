"""A finding: what a run established beyond a limit that is not, by itself, a failure.

One type serves both places the harness records findings:

* a finding-type check (:func:`scatterbench.validation.checks.registry.judge`): a property *of
  a paper* that the run established (a printed Table I entry an independent calculation
  contradicts, a printed equation's slip).  The check gives its verdict, ``fails`` and
  ``fails_if``; its name, measured value and detail are the :class:`~.registry.Check`'s.
* the stability sweep (:mod:`scatterbench.validation.studies.edge_sweep`): what a model does at
  the edges of its parameters and geometries (``model``, ``params``, ``kind``, ``value``,
  ``where``, ``fields``).  Its verdict is not the sweep's to give: each finding is accepted,
  with its reason, by an entry of ``accepted_findings.toml`` whose condition reads ``fields``,
  or it is unaccepted (a failure), so the sweep leaves ``fails`` and ``fails_if`` unset.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

__all__ = ["Finding"]


@dataclass(frozen=True)
class Finding:
    """What a run found (``model``: the model's name, ``params``: its repr, ``kind``: what was
    found, ``value``: its size, ``where``: the geometry or incidence, ``fields``: the numbers an
    accepted finding's condition reads) and its verdict (``fails``: whether the condition that
    makes it a failure holds in this run, ``fails_if``: that condition in words; ``None`` where
    the verdict is given elsewhere, as for the sweep's findings)."""

    model: str = ""
    params: str = ""
    kind: str = ""
    value: float = math.nan
    where: str = ""
    fields: dict = field(default_factory=dict)
    fails: bool | None = None
    fails_if: str | None = None
