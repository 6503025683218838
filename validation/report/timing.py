"""A report's results without what its run's timing decides: what must be identical whatever
the executor (``--workers N``, ``--scheduler``) and however loaded the machine.

Left out: every ``seconds``, the date and the commit; the measured speeds (the speed section's
per-geometry throughput and the threads it ran on); the trade-off's Pareto fronts (which
settings no other beats on cost and error is decided by measured seconds).  Everything else,
every check's measured value and status, every table and tracked number, stays.
"""

from __future__ import annotations

import hashlib
import json

__all__ = ["without_timings", "results_digest"]

#: keys whose values are measured times, anywhere in results.json, and the kernel threads the
#: speed section's throughput was timed on (a worker's share of the cores: the executor's)
_TIMED_KEYS = frozenset(
    {
        "seconds",
        "phase_seconds",
        "date",
        "git_commit",
        "us per geometry (CPU)",
        "us per geometry (wall)",
        "kernel threads",
    }
)
#: per section: the ``numbers`` tables chosen by measured time (prefixes)
_TIMED_TABLES = {"speed": ("pareto|",), "provenance": ("section_times",)}
#: the provenance table's row naming the commit (as ``git_commit`` does in ``meta``): two
#: commits' reports compare equal where their results are (``benchmarks/study_workers.py
#: --baseline``: before, every run against another checkout differed by this row alone)
_COMMIT_ROW = "git commit"


def _strip(value):
    if isinstance(value, dict):
        return {k: _strip(v) for k, v in value.items() if k not in _TIMED_KEYS}
    if isinstance(value, list):
        return [_strip(v) for v in value]
    return value


def without_timings(results: dict) -> dict:
    """A copy of a report's ``results`` (results.json) without the run's timings."""
    out = _strip(results)
    for sid, prefixes in _TIMED_TABLES.items():
        numbers = out.get("sections", {}).get(sid, {}).get("numbers", {})
        for key in [k for k in numbers if k.startswith(prefixes)]:
            del numbers[key]
    prov = out.get("sections", {}).get("provenance", {}).get("numbers", {})
    if isinstance(prov.get("provenance"), list):
        prov["provenance"] = [
            r for r in prov["provenance"] if not (isinstance(r, dict) and r.get("item") == _COMMIT_ROW)
        ]
    return out


def results_digest(results: dict) -> str:
    """A short digest of :func:`without_timings` (equal digests: equal results, timing aside)."""
    text = json.dumps(without_timings(results), sort_keys=True, default=float)
    return hashlib.sha1(text.encode()).hexdigest()[:16]
