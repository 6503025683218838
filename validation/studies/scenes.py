"""Evaluate a scene: in-plane curve and out-of-plane scan of BRDF, eta, P, P_C.

The in-plane curve runs over the signed scattering angle from -89 to +89 deg
(negative: the incidence side, phi = 180 deg); the out-of-plane scan keeps
``theta_r = theta_i`` and runs ``phi_r`` from 0 (specular) to 180 deg
(retroreflection), as in seed 000 Sec. 3.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
import os

import numpy as np

from scatterbench.models import PointSourceBRDF, RoughDiffuseBRDF
from scatterbench.models.geometry import signed_inplane
from scatterbench.models.polarization import ellipsometric
from scatterbench.validation.atomic import atomic_savefig, atomic_write_text

from .tradeoff import KNOBS, at_precision, choose, float32_unavailable

__all__ = ["scan", "scene_csv", "write_scene_outputs"]


def scan(scene, n_inplane=357, n_azimuth=181, model=None, precision="float64"):
    """The in-plane curve and the out-of-plane scan of ``model`` (default the scene's),
    evaluated at ``precision`` (``"float32"`` only where a float32 kernel evaluates the
    model, :func:`scatterbench.validation.studies.tradeoff.at_precision`).  Returns ``(model, rows)``."""

    model = scene.build() if model is None else model
    mueller = model.mueller if precision == "float64" else at_precision(model, precision)
    s_in = np.asarray(scene.polarization, dtype=float)
    ti = scene.theta_i
    x = np.radians(np.linspace(-89.0, 89.0, n_inplane))
    phi = np.radians(np.linspace(0.0, 180.0, n_azimuth))
    rows = {}
    for label, tr, pr, coord in (
        ("in-plane", *signed_inplane(x), np.degrees(x)),
        ("out-of-plane", np.full_like(phi, ti), phi, np.degrees(phi)),
    ):
        S = np.asarray(mueller(ti, tr, pr), dtype=np.float64) @ s_in
        i, eta, pc, p = ellipsometric(S)
        rows[label] = {
            "coord": coord,
            "theta_r_deg": np.degrees(tr),
            "phi_r_deg": np.degrees(pr),
            "brdf": i / s_in[0],
            "eta_deg": np.degrees(eta),
            "P": p,
            "P_C": pc,
        }
    return model, rows


def _pick(knob, tol, notes, **kw):
    """The cheapest measured setting of ``knob`` (run with ``kw``) meeting ``tol`` (the most
    accurate when none does, said so in ``notes``)."""

    r = KNOBS[knob](quick=True, **kw)
    p = choose(r, tol)
    if p is None:
        p = min(r.points, key=lambda q: q.error)
        notes.append(
            f"{knob}: no measured setting reaches {tol:g}; using the most accurate, {p.setting:g} (error {p.error:.2g})"
        )
    else:
        notes.append(f"{knob}: chose {p.setting:g} (measured error {p.error:.2g} <= {tol:g})")
    return p.setting


def _choose_precision(model, tol, notes):
    """``"float32"`` when a float32 kernel evaluates ``model`` and its float32 error,
    measured on ``model`` itself, meets ``tol`` at a lower cost, else ``"float64"``."""

    reason = float32_unavailable(model)
    if reason is not None:
        notes.append(f"precision: float64 ({reason})")
        return "float64"
    bits = _pick("precision", tol, notes, model=model)
    return "float32" if bits == 32 else "float64"


def choose_settings(scene, tol):
    """Settings for ``tol`` from the measured speed/accuracy curves (validation.studies.tradeoff).

    Returns ``(model, n_inplane, precision, notes)``: the cheapest in-plane grid, Monte
    Carlo pair count, point-source resolution and evaluation precision whose *measured*
    error meets ``tol`` (the first three on the representative configurations of the
    tradeoff study, the precision on the scene's own model), or the most accurate
    measured setting, said so, when none does.
    """

    notes = []
    n_inplane = int(_pick("in-plane grid", tol, notes))
    model = scene.build()
    inner = model.model if isinstance(model, PointSourceBRDF) else model
    if isinstance(inner, RoughDiffuseBRDF):
        pairs = int(_pick("Monte Carlo pairs", tol, notes))
        inner = dataclasses.replace(inner, pairs=pairs)
        model = dataclasses.replace(model, model=inner) if isinstance(model, PointSourceBRDF) else inner
    if isinstance(model, PointSourceBRDF):
        model = dataclasses.replace(model, resolution=int(_pick("point-source resolution", tol, notes)))
    return model, n_inplane, _choose_precision(model, tol, notes), notes


def scene_csv(scene, model, rows) -> str:
    """The scans as CSV text: ``#`` comment lines (scene, file, model, incident Stokes
    vector, each user string JSON-quoted so a newline in it cannot start a row), then a
    header and one row per point, written by the csv module."""
    buf = io.StringIO()
    for key, value in (
        ("scene", scene.name),
        ("file", str(scene.path)),
        ("model", repr(model)),
        ("incident Stokes", str(list(scene.polarization))),
    ):
        buf.write(f"# {key}: {json.dumps(value)}\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["scan", "theta_i_deg", "theta_r_deg", "phi_r_deg", "brdf", "eta_deg", "P", "P_C"])
    ti_deg = math.degrees(scene.theta_i)
    for label, r in rows.items():
        for k in range(len(r["brdf"])):
            w.writerow(
                [label, f"{ti_deg:.6g}", f"{r['theta_r_deg'][k]:.6g}", f"{r['phi_r_deg'][k]:.6g}"]
                + [f"{r[c][k]:.10g}" for c in ("brdf", "eta_deg", "P", "P_C")]
            )
    return buf.getvalue()


#: below this degree of polarization eta is undefined (and the light unpolarized)
P_FLOOR = 1e-12


def _unpolarized(r) -> bool:
    """No polarization anywhere the scan receives light (e.g. an unpolarized source on a
    depolarizing model): its eta, P and P_C panels would be flat zeros."""
    lit = r["brdf"] > 0
    return bool(lit.any()) and bool(np.all(np.abs(r["P"][lit]) < P_FLOOR))


def _plot_scan(axes, label, r, ti_deg):
    """One column of the figure: BRDF (zero BRDF a gap: no light there, nothing to draw on a
    log axis), eta, P, P_C (gaps where undefined), or one "unpolarized" note for all three."""
    ax = axes[0]
    lit = r["brdf"] > 0
    ax.semilogy(r["coord"], np.where(lit, r["brdf"], np.nan))
    if not lit.any():
        ax.text(0.5, 0.5, "no light reaches this scan (BRDF = 0)", ha="center", transform=ax.transAxes)
    ax.set_ylabel("BRDF (1/sr)")
    ax.set_title(f"{label}, theta_i = {ti_deg:g} deg")
    if _unpolarized(r):
        for ax, name in zip(axes[1:], ("eta (deg)", "P", "P_C"), strict=True):
            ax.text(
                0.5, 0.5, f"unpolarized (P < {P_FLOOR:g}): eta undefined, P = P_C = 0",
                ha="center", va="center", transform=ax.transAxes,
            )  # fmt: skip
            ax.set_ylabel(name)
            ax.set_yticks([])
        return
    # eta is defined modulo 180 deg where the light is polarized: unwrap it there for the plot
    # (the CSV keeps (-90, 90])
    ok = lit & np.isfinite(r["eta_deg"]) & (np.abs(np.nan_to_num(r["P"])) >= P_FLOOR)
    eta = np.full(len(ok), np.nan)
    eta[ok] = np.degrees(np.unwrap(np.radians(2 * r["eta_deg"][ok])) / 2)
    axes[1].plot(r["coord"], eta)
    axes[1].set_ylabel("eta (deg)")
    for ax, key in ((axes[2], "P"), (axes[3], "P_C")):
        ax.plot(r["coord"], np.where(lit, r[key], np.nan))
        ax.set_ylabel(key)


def write_scene_outputs(scene, out_dir, tol=None):
    """Write ``<stem>.csv`` and ``<stem>.png``; returns their paths (and notes on the
    settings chosen for ``tol``)."""
    import matplotlib  # matplotlib (heavy): loaded only where a figure is drawn

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # matplotlib (heavy): loaded only where a figure is drawn

    notes = []
    if tol is None:
        model, rows = scan(scene)
    else:
        chosen, n_inplane, precision, notes = choose_settings(scene, tol)
        model, rows = scan(scene, n_inplane=max(n_inplane, 3), model=chosen, precision=precision)
    stem = os.path.splitext(os.path.basename(scene.path))[0]
    csv_path = os.path.join(out_dir, f"{stem}.csv")
    atomic_write_text(csv_path, scene_csv(scene, model, rows))
    fig, axes = plt.subplots(4, 2, figsize=(10, 10), sharex="col")
    ti_deg = math.degrees(scene.theta_i)
    for col, (label, r) in enumerate(rows.items()):
        _plot_scan(axes[:, col], label, r, ti_deg)
        xlab = "signed scattering angle (deg)" if label == "in-plane" else "phi_r (deg), theta_r = theta_i"
        axes[3, col].set_xlabel(xlab)
    fig.suptitle(scene.name)
    fig.tight_layout()
    png_path = os.path.join(out_dir, f"{stem}.png")
    atomic_savefig(fig, png_path, dpi=100)
    plt.close(fig)
    if tol is not None:
        return csv_path, png_path, notes
    return csv_path, png_path
