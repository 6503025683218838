"""Optimum, emcee ensemble sampling with autocorrelation-time convergence, resumable chains.

``optimize`` finds the starting optimum: a bounded least-squares fit of the
whitened residuals (noise terms held at their starting values) from several
seeded starts, then, when noise terms are free, a bounded maximization of the
full log posterior from the best of them.

``run_chain`` runs an :class:`emcee.EnsembleSampler` (the stretch move, or
differential evolution: ``ChainSettings.moves``) in
segments of ``check_every`` steps (:class:`~scatterbench.validation.fitting.settings.ChainSettings`),
storing the chain in a :class:`~scatterbench.validation.fitting.checkpoint.CheckpointBackend`.
After each segment the backend estimates the integrated autocorrelation time
``tau`` of every parameter (emcee's ``integrated_time`` on the whole chain,
``c = 5``) and, when it has a path, writes its checkpoint atomically.  The run
stops when ``N >= tau_factor * max(tau)`` and ``max(tau)`` moved by less than
``tau_rtol`` since the previous check ("converged"), or at ``max_steps``
("step budget") and says which.  Segments are aligned to multiples of
``check_every`` steps, and the random state is saved with the chain, so a run
resumed from its checkpoint produces the same chain, bit for bit, as an
uninterrupted one.

All random draws (walker initialization, the moves) happen in this
process from the seed; the executor only maps the log-probability over walkers.
"""

from __future__ import annotations

import contextlib
import math
import time
from dataclasses import dataclass, field
from types import SimpleNamespace

import emcee
import numpy as np
from scipy import optimize as _opt
from tqdm import tqdm

from .checkpoint import CheckpointBackend, CheckpointError
from .executors import _sigint_between_calls
from .settings import ChainSettings

__all__ = [
    "vectorized",
    "optimize",
    "initial_ball",
    "burn_in",
    "run_chain",
    "ChainResult",
    "summarize",
    "CheckpointBackend",
    "CheckpointError",
    "ChainSettings",
]


# ---------------------------------------------------------------------------- optimum
def _default_start(lik, bounds):
    """The scene's values, clipped into the bounds; free noise terms at the middle of their range."""
    start = []
    for p, (lo, hi) in zip(lik.spec.free, bounds, strict=True):
        if p.is_noise:
            start.append(0.5 * (lo + hi))
        else:
            v = float(p.to_u(lik.scene.get_value(p.key)))
            start.append(min(max(v, lo), hi))
    return np.asarray(start, float)


def _least_squares(lik, s, bounds, model_idx):
    """Scene parameters by bounded least squares from ``s`` (noise terms held at ``s``);
    ``None`` when the start gives no finite residuals."""
    s = np.clip(s, bounds[:, 0], bounds[:, 1])

    def resid(v):
        u = s.copy()
        u[model_idx] = v
        return lik.whitened(u)

    lo, hi = bounds[model_idx, 0], bounds[model_idx, 1]
    x0 = np.clip(s[model_idx], lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))
    try:
        r = _opt.least_squares(resid, x0, bounds=(lo, hi), x_scale=hi - lo, max_nfev=400)
    except ValueError:
        return None
    u = s.copy()
    u[model_idx] = r.x
    return u


def _polish_noise(lik, u, val, bounds):
    """Free noise levels: maximize the full log posterior (Powell, bounded) from ``(u, val)``."""

    def neg(v):
        lp = lik(v)
        return -lp if math.isfinite(lp) else 1e300

    r = _opt.minimize(
        neg,
        u,
        method="Powell",
        bounds=list(map(tuple, bounds)),
        options={"xtol": 1e-6, "ftol": 1e-10, "maxfev": 4000},
    )
    lp = lik(r.x)
    return (np.asarray(r.x, float), float(lp)) if lp > val else (u, val)


def optimize(lik, seed, n_starts=4, start=None):
    """Maximum of the log posterior ``lik(u)`` (a :class:`~scatterbench.validation.fitting.likelihood.Likelihood`).

    Parameters
    ----------
    lik : Likelihood
    seed : int
        Seeds the prior draws of the extra starts.
    n_starts : int
        ``start`` and ``n_starts - 1`` draws from the prior.
    start : array_like, optional
        Default: the scene's values, clipped into the bounds; free noise terms at
        the middle of their sampling range.

    Returns
    -------
    u_best : ndarray
    log_post_best : float
    info : dict
        ``starts``, ``start_values`` (the log posterior reached from each) and
        ``sd_u`` (rough posterior standard deviations at the optimum).
    """
    b = lik.spec.u_bounds()
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 1]))
    if start is None:
        start = _default_start(lik, b)
    starts = [np.asarray(start, float)] + [rng.uniform(b[:, 0], b[:, 1]) for _ in range(n_starts - 1)]
    model_idx = [i for i, p in enumerate(lik.spec.free) if not p.is_noise]
    best, tried = None, []
    for s in starts:
        u = _least_squares(lik, s, b, model_idx)
        if u is None:
            continue
        val = lik(u)
        tried.append(float(val))
        if best is None or val > best[1]:
            best = (u, val)
    if best is None:
        raise ValueError("optimize: no start gave a finite likelihood; check the bounds and the data")
    u, val = best
    if len(model_idx) < len(lik.spec.free):
        u, val = _polish_noise(lik, u, val, b)
    return u, float(val), {"starts": len(starts), "start_values": tried, "sd_u": _posterior_sd(lik, u)}


def _posterior_sd(lik, u):
    """Rough posterior standard deviations (sampling coordinates) at the optimum, to size
    the walkers' starting ball: Gauss-Newton ``(J^T J)^-1`` of the whitened residuals for
    scene parameters; ``1/sqrt(2N)`` in ln(level) for noise levels (the relative
    spread of a variance estimated from ``N`` residuals)."""
    spec = lik.spec
    b = spec.u_bounds()
    width = b[:, 1] - b[:, 0]
    sd = 1e-3 * width
    model_idx = [i for i, p in enumerate(spec.free) if not p.is_noise]
    h = 1e-6 * width[model_idx]
    r0 = lik.whitened(u)
    J = []
    for j, i in enumerate(model_idx):
        v = u.copy()
        v[i] = u[i] + h[j] if u[i] + h[j] <= b[i, 1] else u[i] - h[j]
        J.append((lik.whitened(v) - r0) / (v[i] - u[i]))
    J = np.array(J).T
    try:
        cov = np.linalg.inv(J.T @ J)
        d = np.sqrt(np.diag(cov))
        if np.all(np.isfinite(d)) and np.all(d > 0):
            sd[model_idx] = np.minimum(d, width[model_idx])
    except np.linalg.LinAlgError:
        pass
    n = lik.n_points
    for i, p in enumerate(spec.free):
        if p.is_noise:
            rel = 1.0 / math.sqrt(2.0 * n)
            sd[i] = rel if p.prior == "log" else rel * max(abs(p.from_u(u[i])), 1e-12)
    return sd


def initial_ball(u0, nwalkers, seed, bounds, sd=None, scale=0.5):
    """Walkers in a Gaussian ball around ``u0`` inside the bounds: ``scale`` x the estimated
    posterior standard deviations ``sd`` (default: 1e-3 of the prior width).

    A ball much smaller than the posterior takes many autocorrelation times to
    expand and, if the chain is short, gives intervals that are too narrow."""
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 2]))
    b = np.asarray(bounds, float)
    width = b[:, 1] - b[:, 0]
    step = scale * np.asarray(sd, float) if sd is not None else 1e-3 * width
    p = u0 + step * rng.standard_normal((nwalkers, len(u0)))
    # reflect into the box (keeps the ball's spread next to a bound)
    p = np.where(p < b[:, 0], 2 * b[:, 0] - p, p)
    p = np.where(p > b[:, 1], 2 * b[:, 1] - p, p)
    return np.clip(p, b[:, 0], b[:, 1])


# ---------------------------------------------------------------------------- chain
@dataclass
class ChainResult:
    chain: np.ndarray  # (steps, walkers, ndim), sampling coordinates
    log_prob: np.ndarray  # (steps, walkers)
    accepted: np.ndarray  # (walkers,)
    tau: np.ndarray  # last estimate, (ndim,)
    tau_history: list = field(default_factory=list)  # (steps, tau) per check
    converged: bool = False
    stop_reason: str = ""
    seconds: float = 0.0
    evaluations: int = 0

    @property
    def steps(self):
        return self.chain.shape[0]

    @property
    def acceptance(self):
        return self.accepted / max(self.steps, 1)

    @property
    def evals_per_second(self):
        return self.evaluations / self.seconds if self.seconds > 0 else float("nan")

    def burn_thin(self):
        """Burn-in ``2 max(tau)`` and thinning ``max(1, min(tau) / 2)`` (emcee's advice)."""
        tmax = float(np.max(self.tau)) if np.all(np.isfinite(self.tau)) else self.steps / 4
        tmin = float(np.min(self.tau)) if np.all(np.isfinite(self.tau)) else 1.0
        burn = int(math.ceil(2 * tmax))
        if burn >= self.steps:  # not converged: keep the second half, and say so in the summary
            burn = self.steps // 2
        return burn, max(1, int(0.5 * tmin))

    def samples(self):
        burn, thin = self.burn_thin()
        return self.chain[burn::thin].reshape(-1, self.chain.shape[2])


def _converged(tau_history, settings):
    """N >= tau_factor * max(tau), and max(tau) moved by < tau_rtol since the previous check."""
    if len(tau_history) < 2:
        return False
    (steps, tau), (_, prev) = tau_history[-1], tau_history[-2]
    if not (np.all(np.isfinite(tau)) and np.all(np.isfinite(prev))):
        return False
    return bool(
        steps >= settings.tau_factor * tau.max()
        and abs(tau.max() - prev.max()) < settings.tau_rtol * tau.max()
    )


def _first_state(backend, settings, p0):
    """Where the sampler starts: the checkpoint's last ensemble and random state, or ``p0``
    with a random state from the seed."""
    if backend.initialized and backend.iteration > 0:
        if backend.nwalkers != settings.walkers:
            raise CheckpointError(
                f"{backend.path}: the checkpoint has {backend.nwalkers} walkers, the settings {settings.walkers}"
            )
        settings.require_walkers(backend.ndim)
        return backend.get_last_sample()
    if p0 is None:
        raise ValueError("p0: the walkers' starting positions are needed for a new chain")
    if isinstance(p0, emcee.State):  # a burn-in's end (burn_in): its ensemble and random state
        settings.require_walkers(p0.coords.shape[1])
        return emcee.State(p0.coords, random_state=p0.random_state)
    p0 = np.asarray(p0, float)
    if p0.ndim != 2 or p0.shape[0] != settings.walkers:
        raise ValueError(f"p0: expected shape (walkers = {settings.walkers}, ndim); got {p0.shape}")
    settings.require_walkers(p0.shape[1])
    return emcee.State(p0, random_state=np.random.RandomState(settings.seed % 2**32).get_state())


@contextlib.contextmanager
def _progress_bar(show, total, initial=0, unit="step", desc="emcee"):
    """A tqdm bar (``show``) over ``total`` (the step budget of a chain; the fits of a
    recovery study), else a stand-in that does nothing."""
    if not show:
        yield SimpleNamespace(update=lambda n: None)
        return

    bar = tqdm(total=total, initial=initial, unit=unit, desc=desc, mininterval=1.0)
    try:
        yield bar
    finally:
        bar.close()


def vectorized(log_prob) -> bool:
    """True when ``log_prob`` evaluates many positions at once (a ``batch`` method, as
    :class:`~scatterbench.validation.fitting.likelihood.Likelihood` has): the sampler then hands it every
    walker of a step in one call."""
    return callable(getattr(log_prob, "batch", None))


class _Batched:
    """``log_prob.batch`` over the walkers of a step, ``(n, k) -> (n,)``: in one call, or with
    an executor of several workers, one contiguous share of the walkers per worker (the
    results are the same: each walker's value does not depend on the others)."""

    def __init__(self, log_prob, executor):
        self.fn = log_prob.batch  # one object: an executor ships it to its workers once
        self.executor = executor
        self.parts = max(1, int(getattr(executor, "workers", 1))) if executor is not None else 1

    def __call__(self, P):
        if self.parts == 1:
            return self.fn(P)
        shares = [c for c in np.array_split(P, self.parts) if len(c)]
        return np.concatenate(self.executor.map(self.fn, shares))


def _moves(name):
    """emcee's moves for :attr:`ChainSettings.moves` (new objects: a move holds no state
    across steps, but one per sampler keeps runs independent)."""
    if name == "de":
        return [(emcee.moves.DEMove(), 0.8), (emcee.moves.DESnookerMove(), 0.2)]
    return emcee.moves.StretchMove()


def run_chain(log_prob, settings=None, *, p0=None, backend=None, executor=None, progress=False):
    """Run (or resume) the ensemble until converged or out of steps; see the module docstring.

    Parameters
    ----------
    log_prob : callable
        Log posterior of one walker's position (picklable for a process executor); with a
        ``batch`` method (:func:`vectorized`) the sampler evaluates every walker of a step in
        one call (``emcee``'s ``vectorize=True``).
    settings : ChainSettings, optional
        Walkers, seed, step budget, check interval and stopping rule (default:
        ``ChainSettings()``).
    p0 : ndarray, shape (walkers, ndim), or emcee.State, optional
        Starting positions of a new chain (ignored when ``backend`` holds one); a state
        (:func:`burn_in`'s) gives the random state too.
    backend : CheckpointBackend, optional
        Where the chain is kept (and saved, if it has a path): a new one, or
        :meth:`CheckpointBackend.load` to resume.  Default: memory only.
    executor : optional
        Maps the log posterior over walkers (``map(fn, items)``), or over shares of them for a
        vectorized ``log_prob``.
    progress : bool
        Show a progress bar.

    Returns
    -------
    ChainResult
    """
    settings = ChainSettings() if settings is None else settings
    backend = CheckpointBackend() if backend is None else backend
    state = _first_state(backend, settings, p0)
    common = dict(backend=backend, moves=_moves(settings.moves))
    if vectorized(log_prob):
        fn = _Batched(log_prob, executor)
        sampler = emcee.EnsembleSampler(settings.walkers, state.coords.shape[1], fn, vectorize=True, **common)
    else:
        sampler = emcee.EnsembleSampler(
            settings.walkers, state.coords.shape[1], log_prob, pool=executor, **common
        )
    with _progress_bar(progress, settings.max_steps, backend.iteration) as bar:
        while backend.iteration < settings.max_steps and not _converged(backend.tau_history, settings):
            done = backend.iteration
            # segments end on multiples of check_every, so a resumed run checks where the original did
            n = min(settings.check_every - done % settings.check_every, settings.max_steps - done)
            t0 = time.perf_counter()
            _segment(sampler, state, n, bar, hold_sigint=vectorized(log_prob))
            backend.end_segment(time.perf_counter() - t0)
            state = backend.get_last_sample()  # the ensemble and random state after the segment
    return _result(backend, settings)


def burn_in(log_prob, settings, p0, executor=None):
    """``settings.burn`` steps from ``p0``, not kept: ``(state, seconds)``, the ensemble and
    random state they end in (:func:`run_chain`'s ``p0`` for the kept chain, which then
    continues them bit for bit) and their wall time."""
    backend = CheckpointBackend()
    t0 = time.perf_counter()
    burn = settings.replace(max_steps=settings.burn, check_every=settings.burn, burn=0)
    run_chain(log_prob, burn, p0=p0, backend=backend, executor=executor)
    return backend.get_last_sample(), time.perf_counter() - t0


def _segment(sampler, state, n, bar, hold_sigint):
    """``n`` steps from ``state``.  ``hold_sigint``: Ctrl-C is held until the step ends and
    raised there, as the executors do between per-walker calls: a vectorized log-probability
    runs inside emcee's wrapper, which prints a traceback for an exception raised in it."""

    with _sigint_between_calls() if hold_sigint else contextlib.nullcontext(lambda: False) as pending:
        for _ in sampler.sample(state, iterations=n, store=True):
            bar.update(1)
            if pending():
                break  # the interrupt is raised when the block closes, the step stored


def _unsettled(hist, settings):
    """Why a chain whose last ``N >= tau_factor * max(tau)`` is still not converged: a single
    autocorrelation estimate, or ``max(tau)`` still moving (the rule needs both); else ``""``."""
    if not hist or _converged(hist, settings) or hist[-1][0] < settings.tau_factor * np.max(hist[-1][1]):
        return ""
    if len(hist) < 2:
        return " (N is, but tau was estimated once: its stability is untested; check more often)"
    moved = abs(np.max(hist[-1][1]) - np.max(hist[-2][1])) / np.max(hist[-1][1])
    return f" (N is, but max(tau) moved by {moved:.0%} since the previous check, more than tau_rtol = {settings.tau_rtol:g})"


def _result(backend, settings) -> ChainResult:
    """The chain in ``backend`` with its convergence verdict and the reason it stopped."""
    hist, f = backend.tau_history, settings.tau_factor
    tau = hist[-1][1] if hist else np.full(backend.ndim, np.nan)
    converged = _converged(hist, settings)
    if converged:
        reason = f"converged: N = {hist[-1][0]} >= {f:g} tau = {f * tau.max():.0f}"
    else:
        reason = (
            f"step budget reached: N = {backend.iteration} (max_steps), {f:g} tau = "
            f"{f * np.max(tau):.0f}: NOT converged by the N >= {f:g} tau rule{_unsettled(hist, settings)}"
        )
    return ChainResult(
        chain=backend.get_chain(),
        log_prob=backend.get_log_prob(),
        accepted=backend.accepted.copy(),
        tau=tau,
        tau_history=list(hist),
        converged=converged,
        stop_reason=reason,
        seconds=backend.seconds,
        evaluations=backend.evaluations,
    )


#: a sample within this fraction of its parameter's sampling-coordinate range from a bound is
#: "at" the bound (:func:`at_bounds`)
BOUND_BAND = 0.01


def at_bounds(u, bounds):
    """Per parameter, the fraction of samples ``u`` ``(S, k)`` within :data:`BOUND_BAND` of the
    sampling-coordinate range of either bound (``bounds`` ``(k, 2)``): a posterior pressed
    against its prior box (a model that reaches the data only at the box's edge, or bounds
    too narrow), which also mixes slowly there.  Uniform samples give about 0.02."""
    b = np.asarray(bounds, float)
    band = BOUND_BAND * (b[:, 1] - b[:, 0])
    return np.mean((u <= b[:, 0] + band) | (u >= b[:, 1] - band), axis=0)


def summarize(result: ChainResult, spec):
    """Posterior summary in physical units: percentiles, mean, std, correlations, and the
    fraction of samples at a bound (:func:`at_bounds`)."""
    u = result.samples()
    x = np.column_stack([p.from_u(u[:, i]) for i, p in enumerate(spec.free)])
    near = at_bounds(u, spec.u_bounds())
    q = np.percentile(x, [2.5, 16, 50, 84, 97.5], axis=0)
    burn, thin = result.burn_thin()
    params = {}
    for i, p in enumerate(spec.free):
        params[p.key] = {
            "median": float(q[2, i]),
            "p2.5": float(q[0, i]),
            "p16": float(q[1, i]),
            "p50": float(q[2, i]),
            "p84": float(q[3, i]),
            "p97.5": float(q[4, i]),
            "mean": float(x[:, i].mean()),
            "std": float(x[:, i].std(ddof=1)) if len(x) > 1 else float("nan"),
            "tau_steps": float(result.tau[i]),
            "prior": p.prior,
            "bounds": [p.low, p.high],
            "at_bound": float(near[i]),
        }
    corr = np.corrcoef(x.T) if x.shape[1] > 1 else np.ones((1, 1))
    i_best = np.unravel_index(np.argmax(result.log_prob), result.log_prob.shape)
    best_u = result.chain[i_best]
    return {
        "parameters": params,
        "correlations": {"order": spec.names, "matrix": np.atleast_2d(corr).tolist()},
        "max_log_posterior_in_chain": float(result.log_prob[i_best]),
        "best_in_chain": {p.key: float(p.from_u(best_u[i])) for i, p in enumerate(spec.free)},
        "sampling": {
            "walkers": int(result.chain.shape[1]),
            "steps": int(result.steps),
            "tau_steps": [float(t) for t in result.tau],
            "tau_max": float(np.max(result.tau)),
            "steps_over_tau_max": float(result.steps / np.max(result.tau)),
            "acceptance_mean": float(result.acceptance.mean()),
            "acceptance_min": float(result.acceptance.min()),
            "acceptance_max": float(result.acceptance.max()),
            "burn_in": burn,
            "thin": thin,
            "independent_samples_approx": float(result.steps * result.chain.shape[1] / np.max(result.tau)),
            "posterior_samples_kept": int(len(x)),
            "converged": bool(result.converged),
            "stop_reason": result.stop_reason,
            "seconds": float(result.seconds),
            "log_prob_evaluations": int(result.evaluations),
            "evaluations_per_second": float(result.evals_per_second),
        },
    }
