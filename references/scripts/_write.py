"""Shared by the peer-reference scripts: write a CSV with a ``#`` provenance header."""

from __future__ import annotations

import csv
import os

import numpy as np

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data")


def write_csv(name, provenance, header, rows):
    """Write ``../data/NAME``: ``provenance`` lines (each prefixed ``# ``), the header,
    and the rows with floats written exactly (``repr``)."""
    path = os.path.join(DATA, name)
    with open(path, "w", newline="") as fh:
        for line in provenance:
            fh.write(f"# {line}\n")
        w = csv.writer(fh)
        w.writerow(header)
        for r in rows:
            w.writerow([repr(float(x)) if isinstance(x, (float, np.floating)) else x for x in r])
    print(f"wrote {len(rows)} rows to {path}")
