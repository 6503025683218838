"""Between-chain convergence: the rank-normalized split R-hat of Vehtari, Gelman, Simpson,
Carpenter & Burkner, "Rank-normalization, folding, and localization: an improved R-hat for
assessing convergence of MCMC", Bayesian Analysis 16, 667 (2021), Sec. 4, as ArviZ computes it
(``arviz.rhat(method="rank")``; ArviZ is a dependency for the real-data study's model comparison
too).  Chains agree to within their sampling error below about 1.01.
"""

from __future__ import annotations

import functools
import math
import threading

import numpy as np

__all__ = ["rhat", "chain_seed", "load"]


def chain_seed(seed: int, index: int) -> int:
    """The seed of chain ``index`` of a run seeded ``seed``: chain 0 keeps ``seed`` (so one
    chain is the run it always was), the others are drawn from ``SeedSequence([seed, index])``;
    the seeds do not depend on where the chains run."""
    if index == 0:
        return int(seed)
    return int(np.random.SeedSequence([int(seed), int(index)]).generate_state(1)[0])


#: one thread at a time runs :func:`load`: a report's thread runs it while the sections that use
#: ArviZ start, and they call it too before they use ArviZ (they then wait for that run)
_LOADING = threading.Lock()


def load():
    """Import ArviZ (about 2 s) and run it once on a tiny posterior (0.4-0.6 s, ad hoc): what the
    comparison's R-hat and the PTFE study need, loaded where they will run.  ArviZ's first
    InferenceData makes xarray import ~140 more modules (``dask.array``, the chunk managers'
    entry points, ``psutil``...; ad hoc, 2026-12-07), and imports on threads side by side can
    cross (877275d: a half-imported ``dask.array``), so one thread at a time runs this (a
    lock), and whoever uses ArviZ on a thread beside others calls it first: a report's main
    thread runs it (:attr:`~scatterbench.validation.report.core.SectionSpec.preloads`), and
    the sections that use ArviZ wait for it there.  Once per process."""
    with _LOADING:
        _load()


@functools.cache
def _load():
    import warnings

    import arviz

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a posterior of four draws: its diagnostics warn
        draws = np.arange(8.0).reshape(2, 4)
        idata = arviz.from_dict(posterior={"x": draws}, log_likelihood={"y": draws[..., None]})
        arviz.loo(idata)
        arviz.waic(idata)
        rhat(draws)


def rhat(draws) -> float:
    """Rank-normalized split R-hat of one quantity's ``draws`` (chains, draws per chain), at
    least 2 chains or 4 draws; ``nan`` when there are fewer (nothing to compare)."""
    x = np.asarray(draws, dtype=float)
    if x.ndim != 2:
        raise ValueError(f"draws must be (chains, draws); got shape {x.shape}")
    half = x.shape[1] // 2
    if half < 2 or not np.all(np.isfinite(x)):
        return math.nan
    import arviz  # seconds to import: loaded when a comparison has chains to compare

    return float(arviz.rhat(x, method="rank"))
