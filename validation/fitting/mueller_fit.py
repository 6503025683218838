"""A fit to Mueller-matrix BRDF data, written and read back: ``posterior.json`` and
``posterior_samples.npz`` beside the chain, and the posterior predictive at the rows of any
Mueller data file (``scatterbench predict``).

The fit itself is :func:`~scatterbench.validation.fitting.fit.run_fit` on a
:class:`~.mueller_likelihood.MuellerLikelihood` (the same optimizer, emcee ensemble, checkpoints
and stopping rule as every fit).  The posterior predictive includes the measurement noise: each
draw's M11 is ``c M11_model exp(s_11 z)`` (the calibration scale and the log-normal noise of the
likelihood) and each normalized element ``N_model + s_ij z``, so its intervals are those a new
measurement should fall in.
"""

from __future__ import annotations

import io
import json
import os

import numpy as np

from scatterbench.models import scene as scene_mod
from scatterbench.validation.atomic import atomic_write_bytes, atomic_write_json, atomic_write_text

from .datafile import DataFileError
from .fit import TIMING, _truth_check, information_criteria
from .fitspec import FitSpecError
from .mueller_data import ELEMENTS, NIST_COLUMNS, load_mueller_data
from .mueller_likelihood import MuellerLikelihood, Rows
from .mueller_spec import mueller_spec_from

__all__ = [
    "is_mueller_file",
    "mueller_likelihood",
    "write_mueller_fit",
    "load_posterior",
    "predictive_draws",
    "predictive_csv",
    "PERCENTILES",
]

#: the percentiles ``scatterbench predict`` writes, with the median first
PERCENTILES = (("median", 50.0), ("p2.5", 2.5), ("p16", 16.0), ("p84", 84.0), ("p97.5", 97.5))
SAMPLES = "posterior_samples.npz"


def is_mueller_file(path) -> bool:
    """Whether ``path`` is a Mueller-matrix data file (a ``# basis:`` or ``# format:
    scatterbench-mueller/1`` line, or NIST's published header) rather than a Stokes-vector
    data file; ``False`` when it cannot be read (the reader then says why)."""
    try:
        with open(path, encoding="utf-8-sig", errors="replace") as fh:
            for line in fh:
                s = line.strip()
                if not s:
                    continue
                if s.startswith("#"):
                    if s[1:].strip().startswith(("basis:", "format: scatterbench-mueller")):
                        return True
                    continue
                return tuple(f.strip() for f in s.split(",")) == NIST_COLUMNS
    except OSError:
        return False
    return False


def mueller_likelihood(scene, data, free=None) -> MuellerLikelihood:
    """The likelihood of ``data`` (a MuellerData) for ``scene``'s ``[fit]`` table (``free``:
    command-line entries replacing its free list)."""
    return MuellerLikelihood(scene, mueller_spec_from(scene, data.wavelength_nm, free), data)


def interval_coverage(lik, samples, data, rows, rng, n_draws=200) -> dict:
    """Fraction of the rows of ``data`` inside the 68% / 95% posterior-predictive intervals of
    ``samples`` evaluated at ``rows`` (``data``'s geometry), per fitted element and ``"all"``
    pooled: the fit's predictive check and the study's held-out coverage."""
    pick = rng.choice(len(samples), size=min(n_draws, len(samples)), replace=False)
    rep = predictive_draws(lik, samples[pick], rows, rng)
    N = data.normalized()
    out, pooled = {}, {"68": [], "95": []}
    for name in lik.elements:
        e = ELEMENTS.index(name)
        obs = data.mueller[:, 0, 0] if e == 0 else N[:, e // 4, e % 4]
        lo68, hi68, lo95, hi95 = np.percentile(rep[e], [16, 84, 2.5, 97.5], axis=0)
        in68, in95 = (obs >= lo68) & (obs <= hi68), (obs >= lo95) & (obs <= hi95)
        pooled["68"].append(in68)
        pooled["95"].append(in95)
        out[name] = {"inside_68": float(in68.mean()), "inside_95": float(in95.mean()), "rows": len(obs)}
    out["all"] = {
        "inside_68": float(np.concatenate(pooled["68"]).mean()),
        "inside_95": float(np.concatenate(pooled["95"]).mean()),
        "rows": len(data),
    }
    return out


def _coverage(lik, samples, seed, n_draws=200):
    """:func:`interval_coverage` of the fitted rows, per element (``posterior.json``)."""
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 3]))
    out = interval_coverage(lik, samples, lik.data, lik.rows, rng, n_draws)
    del out["all"]
    return out


def write_mueller_fit(fit, out, *, data_path, scene_path, executor_desc=""):
    """``posterior.json`` (strict JSON; wall-clock measurements under ``timing``) and
    ``posterior_samples.npz`` (the kept samples in sampling coordinates), atomically."""
    os.makedirs(out, exist_ok=True)
    lik = fit.lik
    samples = fit.chain.samples()
    post = dict(fit.summary)
    sampling = dict(post["sampling"])
    post["sampling"] = {k: v for k, v in sampling.items() if k not in TIMING}
    post["timing"] = {new: sampling[old] for old, new in TIMING.items() if old in sampling}
    post["timing"]["note"] = "wall-clock measurements: they differ between runs that are otherwise identical"
    if lik.data_all.meta.get("truth"):
        post["truth_check"] = _truth_check(post["parameters"], lik.data_all.meta["truth"])
    raw = dict(lik.base_scene.raw, fit=lik.spec.as_dict())
    post.update(
        {
            "kind": "mueller",
            "data": {
                "path": data_path,
                "rows": len(lik.data_all),
                "used_rows": len(lik.data),
                "basis": lik.data.basis,
                "elements": list(lik.elements),
                "wavelengths_nm": list(lik.spec.wavelengths),
            },
            "scene": {"path": scene_path, "name": lik.scene.name, "resolved": raw},
            "spec": lik.spec.as_dict(),
            "optimum": fit.optimum,
            "information_criteria": information_criteria(fit),
            "posterior_predictive": _coverage(lik, samples, fit.settings.seed),
            "settings": dict(fit.settings.as_dict(), executor=executor_desc),
        }
    )
    buf = io.BytesIO()
    np.savez(buf, u=samples, names=np.array(lik.spec.names))
    atomic_write_bytes(os.path.join(out, SAMPLES), buf.getvalue())
    atomic_write_json(os.path.join(out, "posterior.json"), post)
    return post


def load_posterior(folder):
    """``(posterior dict, samples (S, k), scene, spec)`` of a Mueller fit written by
    :func:`write_mueller_fit`; a :class:`FitSpecError` naming the file otherwise."""
    path = os.path.join(folder, "posterior.json")
    try:
        with open(path, encoding="utf-8") as fh:
            post = json.load(fh)
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise FitSpecError(f"{path}: cannot read a fit's posterior: {exc}") from None
    if not isinstance(post, dict) or post.get("kind") != "mueller":
        raise FitSpecError(
            f"{path}: kind: not a fit to Mueller-matrix data (scatterbench fit on a Mueller data file)"
        )
    spath = os.path.join(folder, SAMPLES)
    try:
        with np.load(spath) as z:
            samples, names = np.asarray(z["u"], float), [str(n) for n in z["names"]]
    except (OSError, KeyError, ValueError) as exc:
        raise FitSpecError(f"{spath}: cannot read the posterior samples: {exc}") from None
    try:
        sc = scene_mod.from_dict(post["scene"]["resolved"], post["scene"]["path"])
    except (KeyError, TypeError) as exc:
        raise FitSpecError(f"{path}: scene: missing {exc}") from None
    spec = mueller_spec_from(sc, post["data"]["wavelengths_nm"])
    if names != spec.names or samples.ndim != 2 or samples.shape[1] != len(names):
        raise FitSpecError(f"{spath}: names: the samples' parameters {names} are not the fit's {spec.names}")
    return post, samples, sc, spec


def predictive_draws(lik, U, rows, rng, chunk=64) -> dict:
    """Replicated measurements ``{element index: (draws, rows)}`` at ``rows`` (a
    :class:`~.mueller_likelihood.Rows` of all 16 elements) for the positions ``U``: M11 with
    the calibration and log-normal noise, the others normalized with Gaussian noise."""
    out = {e: np.empty((len(U), len(rows))) for e in rows.map}
    for start in range(0, len(U), chunk):
        Ub = U[start : start + chunk]
        P = lik.predict(Ub, rows)
        c, _, noise = lik.nuisance(Ub)
        z = rng.standard_normal((len(rows.map),) + P[0].shape)
        for k, e in enumerate(sorted(rows.map)):
            s = lik.spec.noise_level(ELEMENTS[e], noise)
            if e == 0:
                out[e][start : start + len(Ub)] = c * P[0] * np.exp(s * z[k])
            else:
                out[e][start : start + len(Ub)] = P[e] / P[0] + s * z[k]
    return out


def _rows_for(spec, data):
    """The rows of ``data`` for the fitted posterior; each row's wavelength must be fitted."""
    wl = np.asarray(spec.wavelengths)
    ok = np.any(np.abs(data.wavelength_nm[:, None] - wl[None, :]) <= 1e-6 * wl[None, :], axis=1)
    if not ok.all():
        r = int(np.argmin(ok))
        line = int(data.lines[r]) if data.lines is not None else r + 1
        raise DataFileError(
            data.path,
            line,
            None,
            f"wavelength {data.wavelength_nm[r]:g} nm was not fitted (the posterior has "
            f"{', '.join(f'{w:g}' for w in wl)} nm)",
        )
    return Rows(data, spec.wavelengths, range(16))


def predictive_csv(folder, data_path, n_draws=400, seed=0) -> str:
    """The text of ``scatterbench predict``'s CSV: one row per row of ``data_path``, in its
    order, with the median and the 2.5/16/84/97.5 percentiles of M11 and of each normalized
    element (measurement noise included), in the data file's basis."""
    post, samples, sc, spec = load_posterior(folder)
    data = load_mueller_data(data_path)
    rows = _rows_for(spec, data)
    lik = MuellerLikelihood(sc, spec, data)
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 5]))
    pick = rng.choice(len(samples), size=min(n_draws, len(samples)), replace=False)
    rep = predictive_draws(lik, samples[pick], rows, rng)
    names = ["m11"] + [f"{e}/m11" for e in ELEMENTS[1:]]
    head = [
        f"# posterior predictive of '{post['scene']['name']}' ({post['scene']['path']}) fitted in {folder}",
        f"# at the rows of {data_path}, in their order; {len(pick)} posterior draws, seed {seed}",
        "# the percentiles include the measurement noise of the fit's likelihood (M11: calibration "
        "scale and log-normal noise; normalized elements: Gaussian noise): where a new measurement should fall",
        f"# basis: {data.basis}; m11 in 1/sr; angles in degrees (polar angles >= 0, azimuths in the sample frame)",
    ]
    cols = ["line", "theta_i_deg", "phi_i_deg", "theta_r_deg", "phi_r_deg", "wavelength_nm"]
    cols += [f"{n}_{p}" for n in names for p, _ in PERCENTILES]
    q = [np.percentile(rep[e], [v for _, v in PERCENTILES], axis=0) for e in range(16)]
    geo = np.degrees(np.column_stack([data.theta_i, data.phi_i, data.theta_r, data.phi_r]))
    lines = data.lines if data.lines is not None else np.arange(1, len(data) + 1)
    body = []
    for r in range(len(data)):
        vals = [f"{int(lines[r])}"] + [f"{x:.6g}" for x in geo[r]] + [f"{data.wavelength_nm[r]:g}"]
        vals += [f"{q[e][k, r]:.6g}" for e in range(16) for k in range(len(PERCENTILES))]
        body.append(",".join(vals))
    return "\n".join(head + [",".join(cols)] + body) + "\n"


def write_predictive(folder, data_path, out, n_draws=400, seed=0):
    """Write :func:`predictive_csv` to ``out`` atomically."""
    atomic_write_text(out, predictive_csv(folder, data_path, n_draws, seed))
