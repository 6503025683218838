"""Provenance: package versions, commit, machine, seed, reference data and section run times."""

from __future__ import annotations

import os
import platform
import sys
from dataclasses import dataclass
from importlib import metadata

from scatterbench import references

from ..core import table_block
from ..provenance import git_commit

__all__ = ["ProvenanceData", "compute", "render"]

PACKAGES = ("scatterbench", "numpy", "scipy", "matplotlib", "emcee", "jinja2", "tqdm", "pyscatmech")


@dataclass(frozen=True)
class ProvenanceData:
    """``rows``: (item, value); ``times``: seconds per section computed before this one."""

    rows: tuple
    times: tuple


def _version(pkg):
    try:
        return metadata.version(pkg)
    except metadata.PackageNotFoundError:
        return "not installed"


def compute(ctx):
    """Run after the other sections, whose run times it shows."""
    rows = [{"item": pkg, "value": _version(pkg)} for pkg in PACKAGES]
    rows += [
        {"item": "python", "value": sys.version.split()[0]},
        {"item": "git commit", "value": git_commit()},
        {
            "item": "machine",
            "value": f"{platform.machine()} {platform.processor() or ''} {os.cpu_count()} cores, "
            f"{platform.system()} {platform.release()}",
        },
        {"item": "seed", "value": str(ctx.seed)},
        {
            "item": "reference data",
            "value": "; ".join(
                references.provenance(n).splitlines()[0]
                for n in ("scatmech_facet.csv", "table1_scatmech.csv")
            ),
        },
    ]
    times = tuple(ctx.cache.get("section_times", {}).items())
    return ProvenanceData(tuple(rows), times)


def render(s, d: ProvenanceData):
    s.blocks.append(table_block(s, "provenance", ["item", "value"], d.rows))
    s.blocks.append(
        table_block(
            s,
            "section_times",
            ["section", "seconds"],
            [{"section": k, "seconds": v} for k, v in d.times],
            caption="run time per section (this run)",
        )
    )
