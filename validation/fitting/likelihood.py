"""Likelihood of polarized BRDF data given a scene and a fit spec.

* BRDF: Gaussian in ``ln BRDF``.  Each row's variance is ``f^2 + (brdf_err /
  brdf)^2`` with ``f`` the fractional (speckle) noise ``noise.brdf`` (fixed or
  free).  Speckle is multiplicative, so a log-normal model fits it; the
  ``brdf_err`` column adds the instrument's own relative error.
* Principal angle ``eta``: Gaussian in the residual wrapped to (-90, 90] deg
  (eta is an axis, defined modulo 180 deg), variance ``s_eta^2 + eta_err^2``.
* ``P`` and ``P_C``: Gaussian, variance ``s^2 + err^2``.

A polarization term is used when the data have the quantity and a noise level
for it (``noise.eta_deg``, ``noise.P``, ``noise.P_C``, fixed or free) or the
matching ``*_err`` column, unless the spec turns it off; :attr:`Likelihood.terms` lists what is used.  Rows
removed by the spec's mask do not enter.  A model that predicts no light at a
used row (unreachable geometry) has likelihood zero there.

The detector aperture is the data's: a sidecar that records ``aperture_deg``
replaces the scene's ``[detector]`` (:func:`scene_for_data`).  Whether averaging
over it matters (and the quadrature resolution), and whether a point source
does, is measured once, at the scene's own values
(:meth:`models.scene.Scene.decisions`), and kept for every evaluation, so the
likelihood stays smooth in the parameters.

The log-likelihood omits the data-only Jacobian ``-sum ln brdf_obs`` (a
constant for given data, the same for every model compared on them).
"""

from __future__ import annotations

import math

import numpy as np

from models.polarization import ellipsometric, wrap_axis

from .fitspec import FitSpec

__all__ = ["Likelihood", "scene_for_data", "term_variances", "replicate", "TERMS"]

#: the likelihood's terms, in the order every draw of replicated data takes them
TERMS = ("brdf", "eta", "P", "P_C")


def term_variances(noise: dict, data, terms) -> dict:
    """Per-row variance of each term: the noise level squared (``noise.brdf`` is fractional:
    variance of ln BRDF; ``eta_deg`` in degrees) plus the data's own error column when
    ``data`` has one (``data=None``: the noise levels alone).  A level not given is 0."""
    err = (lambda name: None) if data is None else (lambda name: getattr(data, name))  # noqa: E731
    out = {}
    for t in terms:
        if t == "brdf":
            f = noise.get("brdf", 0.0)
            e = err("brdf_err")
            out[t] = f * f + (0.0 if e is None else (e / data.brdf) ** 2)
        else:
            s = math.radians(noise.get("eta_deg", 0.0)) if t == "eta" else noise.get(t, 0.0)
            e = err(f"{t}_err")
            out[t] = s * s + (0.0 if e is None else e**2)
    return out


def replicate(pred: dict, variances: dict, rng) -> dict:
    """Data drawn from the likelihood's noise model around the model values ``pred``:
    log-normal BRDF, Gaussian eta (wrapped as an axis), P and P_C; one standard-normal
    draw per row for each term of ``variances``, in :data:`TERMS` order."""
    out = {}
    for t in (t for t in TERMS if t in variances):
        m = pred[t]
        z = rng.standard_normal(len(m)) * np.sqrt(variances[t])
        out[t] = m * np.exp(z) if t == "brdf" else (wrap_axis(m + z) if t == "eta" else m + z)
    return out


_LOG2PI = math.log(2.0 * math.pi)


def scene_for_data(scene, data):
    """``scene`` with the detector aperture of ``data``'s sidecar, when it records one
    (the instrument that took the data decides, not the scene's default)."""
    ap = data.meta.get("aperture_deg") if data.meta else None
    if ap is None or float(ap) == scene.aperture_deg:
        return scene
    return scene.with_aperture(float(ap))


class Likelihood:
    """``L(u)``: the log posterior in the spec's sampling coordinates is ``self(u)``."""

    def __init__(self, scene, spec: FitSpec, data):
        self.scene = scene_for_data(scene, data)
        self.spec = spec
        self.data_all = data
        self.mask = spec.mask(data)
        if not self.mask.any():
            raise ValueError(f"{data.path}: mask: every data row is masked out; nothing to fit")
        self.data = data.subset(self.mask)
        d = self.data
        self._log_obs = np.log(d.brdf)
        self._same_incident = bool(np.all(d.incident == d.incident[0]))
        free_noise = {p.key[6:] for p in spec.free if p.is_noise}
        have = lambda t: t in spec.noise or t in free_noise  # noqa: E731
        used = lambda t, col, err: (  # noqa: E731
            t not in spec.off and col is not None and (have(t) or err is not None)
        )
        terms = ["brdf"]
        if not (have("brdf") or d.brdf_err is not None):
            raise ValueError(
                "noise.brdf: the BRDF term needs a noise level (fixed or free: --noise brdf=0.05 or "
                "--noise brdf:0.005:1:log) or a brdf_err column"
            )
        if used("eta_deg", d.eta, d.eta_err):
            terms.append("eta")
        if used("P", d.P, d.P_err):
            terms.append("P")
        if used("P_C", d.P_C, d.P_C_err):
            terms.append("P_C")
        self.terms = tuple(terms)
        self.n_points = len(d)
        # Whether the point source and the aperture matter (and the aperture's quadrature) is
        # decided once, at the scene's own values: re-deciding per evaluation would make ln L
        # jump where a decision flips.
        self.decisions = self.scene.decisions()

    # -- model ---------------------------------------------------------------------
    def model(self, values: dict):
        return self.scene.with_values(self.spec.scene_values(values)).build(decisions=self.decisions)

    def predict(self, model, data=None) -> dict:
        """Model ``brdf, eta, P, P_C`` at the rows of ``data`` (default: the fitted rows)."""
        d = self.data if data is None else data
        M = model.mueller(d.theta_i, d.theta_r, d.phi_r)
        if self._same_incident and data is None:
            S = M @ d.incident[0]
        else:
            S = np.einsum("nij,nj->ni", M, d.incident)
        i, eta, pc, p = ellipsometric(S)
        return {"brdf": i / d.incident[:, 0], "eta": eta, "P": p, "P_C": pc}

    # -- likelihood ----------------------------------------------------------------
    def _variances(self, noise):
        return term_variances(noise, self.data, self.terms)

    def residuals(self, pred) -> dict:
        """Raw residuals (data - model) per term; ln BRDF for the BRDF, radians for eta."""
        d = self.data
        out = {}
        with np.errstate(divide="ignore", invalid="ignore"):
            out["brdf"] = self._log_obs - np.log(pred["brdf"])
        if "eta" in self.terms:
            out["eta"] = wrap_axis(d.eta - pred["eta"])
        if "P" in self.terms:
            out["P"] = d.P - pred["P"]
        if "P_C" in self.terms:
            out["P_C"] = d.P_C - pred["P_C"]
        return out

    def pointwise(self, u) -> np.ndarray:
        """Per-row log-likelihood (all terms summed per row), ``-inf`` where impossible."""
        values = self.spec.physical(u)
        noise = self.spec.noise_values(values)
        pred = self.predict(self.model(values))
        res = self.residuals(pred)
        var = self._variances(noise)
        total = np.zeros(self.n_points)
        for t in self.terms:
            v = np.broadcast_to(var[t], total.shape)
            with np.errstate(divide="ignore", invalid="ignore"):
                ll = -0.5 * (res[t] ** 2 / v + _LOG2PI + np.log(v))
            total += np.where(np.isfinite(ll), ll, -np.inf)
        return total

    def whitened(self, u) -> np.ndarray:
        """Residuals divided by their standard deviations (for least squares); large
        finite values where the model predicts no light."""
        values = self.spec.physical(u)
        noise = self.spec.noise_values(values)
        res = self.residuals(self.predict(self.model(values)))
        var = self._variances(noise)
        out = []
        for t in self.terms:
            with np.errstate(divide="ignore", invalid="ignore"):
                w = res[t] / np.sqrt(np.broadcast_to(var[t], res[t].shape))
            out.append(np.where(np.isfinite(w), w, 1e3))
        return np.concatenate(out)

    def loglike(self, u) -> float:
        return float(np.sum(self.pointwise(u)))

    def __call__(self, u) -> float:
        lp = self.spec.log_prior(u)
        if not math.isfinite(lp):
            return -math.inf
        try:
            ll = self.loglike(u)
        except ValueError:
            # a parameter combination the model rejects (outside its declared range)
            return -math.inf
        return lp + ll if math.isfinite(ll) else -math.inf
