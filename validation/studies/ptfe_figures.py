"""Figures of the PTFE study (:mod:`scatterbench.validation.studies.ptfe`): per incidence angle, the measured and the model
M11 and polarization elements over the scattering hemisphere as polar maps (azimuth
``phi_r``, radius ``theta_r`` in degrees), and the residual map in predictive standard
deviations."""

from __future__ import annotations

import numpy as np

from scatterbench.validation.fitting.mueller_data import ELEMENTS
from scatterbench.validation.fitting.mueller_fit import predictive_draws

__all__ = ["SHOWN", "incidence_maps", "incidence_figure"]

#: the elements drawn: M11 and the normalized elements a diffuser's polarization shows in
SHOWN = ("m11", "m12", "m22", "m33", "m34", "m44")


def incidence_maps(fit, draws=100, seed=0, wavelength_nm=None) -> dict:
    """``{incidence deg: {"phi", "theta", element: (measured, model median, residual/sd)}}``
    over the fitted rows (at ``wavelength_nm`` only, when given: a joint fit's wavelengths
    share their geometries); the model's median and standard deviation are those of the
    posterior predictive (measurement noise included)."""
    lik = fit.lik
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 13]))
    samples = fit.chain.samples()
    pick = rng.choice(len(samples), size=min(draws, len(samples)), replace=False)
    rep = predictive_draws(lik, samples[pick], lik.rows, rng)
    d = lik.data
    N = d.normalized()
    inc = np.round(np.degrees(d.theta_i), 1)  # NIST's normal incidence is 0.001 deg
    at = np.ones(len(d), bool) if wavelength_nm is None else np.abs(d.wavelength_nm - wavelength_nm) < 1e-3
    out = {}
    for a in sorted(set(inc[at].tolist())):
        m = (inc == a) & at
        entry = {"phi": d.phi_r[m], "theta": np.degrees(d.theta_r[m])}
        for name in SHOWN:
            e = ELEMENTS.index(name)
            obs = d.mueller[m, 0, 0] if e == 0 else N[m, e // 4, e % 4]
            r = rep[e][:, m]
            med, sd = np.median(r, axis=0), np.std(r, axis=0)
            entry[name] = (obs, med, (obs - med) / np.where(sd > 0, sd, np.nan))
        out[a] = entry
    return out


def incidence_figure(maps_at, incidence_deg, model_name, plt):
    """One incidence: rows measured / model / residual, one column per element of :data:`SHOWN`."""
    fig, axes = plt.subplots(
        3, len(SHOWN), subplot_kw={"projection": "polar"}, figsize=(2.4 * len(SHOWN), 7.6), squeeze=False
    )
    phi, theta = maps_at["phi"], maps_at["theta"]
    for j, name in enumerate(SHOWN):
        obs, med, res = maps_at[name]
        if name == "m11":
            vals, label = (np.log10(obs), np.log10(med)), "log10 M11 (1/sr)"
            lo, hi = float(np.min(vals)), float(np.max(vals))
            cmap = "viridis"
        else:
            vals, label = (obs, med), f"{name}/m11"
            lim = max(float(np.max(np.abs(np.concatenate(vals)))), 1e-3)
            lo, hi, cmap = -lim, lim, "RdBu_r"
        for i, (v, title) in enumerate(zip(vals, ("measured", "model"), strict=True)):
            sc = axes[i, j].scatter(phi, theta, c=v, s=14, cmap=cmap, vmin=lo, vmax=hi)
            axes[i, j].set_title(f"{title} {label}", fontsize=7)
        fig.colorbar(sc, ax=axes[:2, j], shrink=0.6)
        rs = axes[2, j].scatter(phi, theta, c=res, s=14, cmap="RdBu_r", vmin=-3, vmax=3)
        axes[2, j].set_title(f"residual {name} / pred. sd", fontsize=7)
        fig.colorbar(rs, ax=axes[2, j], shrink=0.6)
        for i in range(3):
            axes[i, j].set_ylim(0, 90)
            axes[i, j].set_yticklabels([])  # the radius (theta_r) labels crowd the small maps
            axes[i, j].tick_params(labelsize=5)
    fig.suptitle(f"PTFE, {model_name}: incidence {incidence_deg:g} deg (radius: theta_r deg; angle: phi_r)")
    return fig
