"""Between-chain convergence: the rank-normalized split R-hat of Vehtari, Gelman, Simpson,
Carpenter & Burkner, "Rank-normalization, folding, and localization: an improved R-hat for
assessing convergence of MCMC", Bayesian Analysis 16, 667 (2021), Sec. 4.

Each chain is split in halves (a chain that drifts then disagrees with itself), the draws of all
the halves are replaced by the normal scores of their ranks (so heavy tails do not hide a
disagreement), and the classic potential scale reduction is computed on them (bulk) and on the
ranks of the distances from the median (tails); R-hat is the larger.  ArviZ computes the same
quantity (``arviz.rhat(method="rank")``); it is not a dependency, and the tests hold this one to
it where it is installed.  Chains agree to within their sampling error below about 1.01.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import ndtri
from scipy.stats import rankdata

__all__ = ["rhat", "chain_seed"]


def chain_seed(seed: int, index: int) -> int:
    """The seed of chain ``index`` of a run seeded ``seed``: chain 0 keeps ``seed`` (so one
    chain is the run it always was), the others are drawn from ``SeedSequence([seed, index])``;
    the seeds do not depend on where the chains run."""
    if index == 0:
        return int(seed)
    return int(np.random.SeedSequence([int(seed), int(index)]).generate_state(1)[0])


def _z_scores(x):
    """Normal scores of the ranks of every draw (ties averaged), shaped as ``x``."""
    r = rankdata(x, method="average").reshape(x.shape)
    return ndtri((r - 0.375) / (x.size + 0.25))


def _psrf(x):
    """The potential scale reduction of ``x`` (chains, draws): Gelman et al., BDA3 Eq. 11.4."""
    m, n = x.shape
    w = float(np.mean(np.var(x, axis=1, ddof=1)))
    b = n * float(np.var(np.mean(x, axis=1), ddof=1))
    if w == 0.0:
        return 1.0 if b == 0.0 else math.inf
    return math.sqrt(((n - 1) / n * w + b / n) / w)


def rhat(draws) -> float:
    """Rank-normalized split R-hat of one quantity's ``draws`` (chains, draws per chain), at
    least 2 chains or 4 draws; ``nan`` when there are fewer (nothing to compare)."""
    x = np.asarray(draws, dtype=float)
    if x.ndim != 2:
        raise ValueError(f"draws must be (chains, draws); got shape {x.shape}")
    half = x.shape[1] // 2
    if half < 2 or not np.all(np.isfinite(x)):
        return math.nan
    split = np.concatenate([x[:, :half], x[:, -half:]], axis=0)
    bulk = _psrf(_z_scores(split))
    tail = _psrf(_z_scores(np.abs(split - np.median(split))))
    return max(bulk, tail)
