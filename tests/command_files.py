"""A good scene (``SCENE``, with its ``[fit]`` table) and a data file it fits (``DATA``), for the
tests that run commands on files (test_bad_inputs, test_distributed), and ``FAST``, the flags
of a fit that stops at once."""

from __future__ import annotations

import math

import numpy as np

from scatterbench import models

ILL = 'name = "x"\n[illumination]\ntheta_i_deg = 45\n'
FACETS = ILL + '[substrate]\nindex = 1.5\ndistribution = "gaussian"\nsigma = 0.2\n'
SCENE = FACETS + '[fit]\nfree = ["substrate.sigma:0.05:1:log"]\n[fit.noise]\nbrdf = 0.05\n'
HEAD = "theta_i_deg,theta_r_deg,phi_r_deg,brdf,incident\n"


def _rows():
    """FACETS' own BRDF at eight in-plane geometries, as data rows."""
    m = models.FacetBRDF(slopes=models.GaussianSlopes(sigma=0.2), substrate=1.5)
    tr = np.radians([5.0, 15.0, 25.0, 35.0, 45.0, 55.0, 65.0, 75.0])
    f = m.brdf(math.radians(45.0), tr, 0.0)
    return "".join(
        f"45,{math.degrees(t):.6g},0,{float(v)!r},unpolarized\n" for t, v in zip(tr, f, strict=True)
    )


ROWS = _rows()
DATA = HEAD + ROWS
#: a fit that stops at once: the data-, scene-, spec- and flag-checks all come before it
FAST = [
    "--walkers",
    "4",
    "--max-steps",
    "4",
    "--check-every",
    "2",
    "--starts",
    "1",
    "--no-progress",
    "--no-plots",
]
