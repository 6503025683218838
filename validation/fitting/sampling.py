"""Optimum, emcee ensemble sampling with autocorrelation-time convergence, resumable chains.

``optimize`` finds the starting optimum: a bounded least-squares fit of the
whitened residuals (noise terms held at their starting values) from several
seeded starts, then, when noise terms are free, a bounded maximization of the
full log posterior from the best of them.

``run_chain`` runs an :class:`emcee.EnsembleSampler` (stretch move) in
segments of ``check_every`` steps.  After each segment it estimates the
integrated autocorrelation time ``tau`` of every parameter (emcee's
``integrated_time`` on the whole chain, ``c = 5``) and writes a checkpoint (the
chain, log-probabilities, acceptance counts, the last ensemble and the
sampler's random state) atomically.  It stops when ``N >= tau_factor *
max(tau)`` and ``max(tau)`` moved by less than ``tau_rtol`` since the previous
check ("converged"), or at ``max_steps`` ("step budget") and says which.
Segments are aligned to multiples of ``check_every`` steps, and the random
state is saved with the ensemble, so a run resumed from its checkpoint
produces the same chain, bit for bit, as an uninterrupted one.

All random draws (walker initialization, the stretch move) happen in this
process from the seed; the executor only maps the log-probability over walkers.
"""

from __future__ import annotations

import io
import json
import math
import os
import time
from dataclasses import dataclass, field

import emcee
import numpy as np
from scipy import optimize as _opt

from validation.atomic import atomic_write_bytes

__all__ = [
    "optimize",
    "initial_ball",
    "run_chain",
    "ChainResult",
    "summarize",
    "CheckpointError",
    "check_walkers",
]


def check_walkers(walkers, ndim):
    """The ensemble needs an even number of walkers, at least two per free parameter
    (emcee's stretch move splits it in halves)."""
    if isinstance(walkers, bool) or not isinstance(walkers, int) or walkers < 2 * ndim or walkers % 2:
        raise ValueError(f"walkers must be even and >= 2 x free parameters ({2 * ndim}); got {walkers!r}")


class CheckpointError(ValueError):
    """A checkpoint that cannot be resumed (missing, or made with other settings)."""


# ---------------------------------------------------------------------------- optimum
def optimize(lik, seed, n_starts=4, start=None):
    """Maximum of the log posterior ``lik(u)`` (a :class:`~validation.fitting.likelihood.Likelihood`).

    Returns ``(u_best, log_post_best, info)``.  Starts: ``start`` (default the
    scene's values, clipped into the bounds; free noise terms at the middle of
    their sampling range) and ``n_starts - 1`` draws from the prior.
    """
    spec = lik.spec
    b = spec.u_bounds()
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 1]))
    if start is None:
        start = []
        for p, (lo, hi) in zip(spec.free, b, strict=True):
            if p.is_noise:
                start.append(0.5 * (lo + hi))
            else:
                v = float(p.to_u(lik.scene.get_value(p.key)))
                start.append(min(max(v, lo), hi))
    starts = [np.asarray(start, float)] + [rng.uniform(b[:, 0], b[:, 1]) for _ in range(n_starts - 1)]
    noise_idx = [i for i, p in enumerate(spec.free) if p.is_noise]
    model_idx = [i for i, p in enumerate(spec.free) if not p.is_noise]
    best = None
    tried = []
    for s in starts:
        s = np.clip(s, b[:, 0], b[:, 1])

        def resid(v, s=s):
            u = s.copy()
            u[model_idx] = v
            return lik.whitened(u)

        lo, hi = b[model_idx, 0], b[model_idx, 1]
        x0 = np.clip(s[model_idx], lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))
        try:
            r = _opt.least_squares(resid, x0, bounds=(lo, hi), x_scale=hi - lo, max_nfev=400)
            u = s.copy()
            u[model_idx] = r.x
        except ValueError:
            continue
        val = lik(u)
        tried.append(float(val))
        if best is None or val > best[1]:
            best = (u, val)
    if best is None:
        raise ValueError("optimize: no start gave a finite likelihood; check the bounds and the data")
    u, val = best
    if noise_idx:

        def neg(v):
            lp = lik(v)
            return -lp if math.isfinite(lp) else 1e300

        r = _opt.minimize(
            neg,
            u,
            method="Powell",
            bounds=list(map(tuple, b)),
            options={"xtol": 1e-6, "ftol": 1e-10, "maxfev": 4000},
        )
        lp = lik(r.x)
        if lp > val:
            u, val = np.asarray(r.x, float), float(lp)
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


def _tau(chain):
    if chain.shape[0] < 10:
        return np.full(chain.shape[2], np.nan)
    return emcee.autocorr.integrated_time(chain, c=5, tol=0, quiet=True)


def _converged(tau_history, tau_factor, tau_rtol):
    """N >= tau_factor * max(tau), and max(tau) moved by < tau_rtol since the previous check."""
    if len(tau_history) < 2:
        return False
    (steps, tau), (_, prev) = tau_history[-1], tau_history[-2]
    if not (np.all(np.isfinite(tau)) and np.all(np.isfinite(prev))):
        return False
    return bool(steps >= tau_factor * tau.max() and abs(tau.max() - prev.max()) < tau_rtol * tau.max())


def _save_checkpoint(path, fingerprint, chain, log_prob, accepted, state, tau_history, seconds, evaluations):
    rs = state.random_state
    buf = io.BytesIO()
    np.savez(
        buf,
        chain=chain,
        log_prob=log_prob,
        accepted=accepted,
        coords=state.coords,
        last_log_prob=state.log_prob,
        rs_name=np.array(rs[0]),
        rs_keys=rs[1],
        rs_pos=np.array(rs[2]),
        rs_has_gauss=np.array(rs[3]),
        rs_cached=np.array(rs[4]),
        fingerprint=np.array(fingerprint),
        tau_history=json.dumps([[s, list(map(float, t))] for s, t in tau_history]),
        seconds=np.array(seconds),
        evaluations=np.array(evaluations),
    )
    atomic_write_bytes(path, buf.getvalue())


def load_checkpoint(path, fingerprint=None):
    if not os.path.exists(path):
        raise CheckpointError(f"{path}: no checkpoint to resume")
    with np.load(path) as z:
        if fingerprint is not None and str(z["fingerprint"]) != fingerprint:
            raise CheckpointError(
                f"{path}: the checkpoint was made with other data, scene, spec, walkers or seed; "
                "resume with the same settings, or start a new run"
            )
        rs = (
            str(z["rs_name"]),
            z["rs_keys"],
            int(z["rs_pos"]),
            int(z["rs_has_gauss"]),
            float(z["rs_cached"]),
        )
        state = emcee.State(z["coords"].copy(), log_prob=z["last_log_prob"].copy(), random_state=rs)
        hist = [(s, np.array(t)) for s, t in json.loads(str(z["tau_history"]))]
        return {
            "chain": z["chain"].copy(),
            "log_prob": z["log_prob"].copy(),
            "accepted": z["accepted"].copy(),
            "state": state,
            "tau_history": hist,
            "seconds": float(z["seconds"]),
            "evaluations": int(z["evaluations"]),
        }


def run_chain(
    log_prob,
    *,
    p0=None,
    seed=0,
    max_steps=20000,
    check_every=100,
    tau_factor=50.0,
    tau_rtol=0.05,
    executor=None,
    checkpoint=None,
    resume=False,
    fingerprint="",
    progress=False,
    resume_from=None,
):
    """Run (or resume) the ensemble; see the module docstring.  ``p0``: (walkers, ndim).

    ``checkpoint``: where checkpoints are written; ``resume``: continue from
    ``resume_from`` (default: ``checkpoint``)."""
    if check_every < 1:
        raise ValueError(f"check_every must be >= 1; got {check_every}")
    if resume:
        ck = load_checkpoint(resume_from or checkpoint, fingerprint)
        chain, lps, accepted, state = ck["chain"], ck["log_prob"], ck["accepted"], ck["state"]
        tau_history, seconds, evaluations = ck["tau_history"], ck["seconds"], ck["evaluations"]
        nwalkers, ndim = state.coords.shape
    else:
        p0 = np.asarray(p0, float)
        nwalkers, ndim = p0.shape
        check_walkers(nwalkers, ndim)
        state = emcee.State(p0, random_state=np.random.RandomState(int(seed) % 2**32).get_state())
        chain = np.empty((0, nwalkers, ndim))
        lps = np.empty((0, nwalkers))
        accepted = np.zeros(nwalkers)
        tau_history, seconds, evaluations = [], 0.0, 0
    sampler = emcee.EnsembleSampler(nwalkers, ndim, log_prob, pool=executor)
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=max_steps, initial=chain.shape[0], unit="step", desc="emcee", mininterval=1.0)
    converged = False
    reason = ""
    try:
        while chain.shape[0] < max_steps:
            if _converged(tau_history, tau_factor, tau_rtol):
                converged = True
                break
            done = chain.shape[0]
            n = min(check_every - done % check_every, max_steps - done)
            t0 = time.perf_counter()
            if state.log_prob is None:
                evaluations += nwalkers  # emcee evaluates the initial ensemble
            sampler.reset()
            for st in sampler.sample(state, iterations=n, store=True):
                state = st
                if bar is not None:
                    bar.update(1)
            seconds += time.perf_counter() - t0
            evaluations += n * nwalkers
            chain = np.concatenate([chain, sampler.get_chain()])
            lps = np.concatenate([lps, sampler.get_log_prob()])
            accepted = accepted + sampler.backend.accepted
            steps = chain.shape[0]
            tau_history.append((steps, _tau(chain)))
            if checkpoint:
                _save_checkpoint(
                    checkpoint, fingerprint, chain, lps, accepted, state, tau_history, seconds, evaluations
                )
        if not converged and _converged(tau_history, tau_factor, tau_rtol):
            converged = True
        if converged:
            steps, tau = tau_history[-1]
            reason = f"converged: N = {steps} >= {tau_factor:g} tau = {tau_factor * tau.max():.0f}"
        else:
            tau = tau_history[-1][1] if tau_history else np.full(ndim, np.nan)
            reason = (
                f"step budget reached: N = {chain.shape[0]} (max_steps), {tau_factor:g} tau = "
                f"{tau_factor * np.max(tau):.0f}: NOT converged by the N >= {tau_factor:g} tau rule"
            )
    finally:
        if bar is not None:
            bar.close()
    return ChainResult(
        chain=chain,
        log_prob=lps,
        accepted=accepted,
        tau=tau_history[-1][1] if tau_history else np.full(ndim, np.nan),
        tau_history=tau_history,
        converged=converged,
        stop_reason=reason,
        seconds=seconds,
        evaluations=evaluations,
    )


def summarize(result: ChainResult, spec):
    """Posterior summary in physical units: percentiles, mean, std, correlations."""
    u = result.samples()
    x = np.column_stack([p.from_u(u[:, i]) for i, p in enumerate(spec.free)])
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
