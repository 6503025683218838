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
(:meth:`scatterbench.models.scene.Scene.decisions`), and kept for every evaluation, so the
likelihood stays smooth in the parameters.

The log-likelihood omits the data-only Jacobian ``-sum ln brdf_obs`` (a
constant for given data, the same for every model compared on them).
"""

from __future__ import annotations

import math

import numpy as np

from scatterbench.models import evaluation
from scatterbench.models.polarization import ellipsometric, wrap_axis
from scatterbench.models.scene import binding

from .fitspec import FitSpec, FitSpecError
from .polarized_kernel import loglike_rows

__all__ = ["Likelihood", "scene_for_data", "term_variances", "replicate", "TERMS"]

#: the likelihood's terms, in the order every draw of replicated data takes them
TERMS = ("brdf", "eta", "P", "P_C")


def term_variances(noise: dict, data, terms) -> dict:
    """Per-row variance of each term: the noise level squared (``noise.brdf`` is fractional:
    variance of ln BRDF; ``eta_deg`` in degrees) plus the data's own error column when
    ``data`` has one (``data=None``: the noise levels alone).  A level not given is 0."""
    err = (lambda name: None) if data is None else (lambda name: getattr(data, name))  # noqa: E731
    out = {}
    # an error column whose square exceeds float64 gives an infinite variance without a
    # warning: ln L is then -inf on those rows, and the fit refuses them by line (fit.FitError)
    with np.errstate(over="ignore"):
        for t in terms:
            out[t] = _variance(t, noise, err, data)
    return out


def _variance(t, noise, err, data):
    """One term's per-row variance (see :func:`term_variances`)."""
    if t == "brdf":
        f = noise.get("brdf", 0.0)
        e = err("brdf_err")
        return f * f + (0.0 if e is None else (e / data.brdf) ** 2)
    s = np.radians(noise.get("eta_deg", 0.0)) if t == "eta" else noise.get(t, 0.0)
    e = err(f"{t}_err")
    return s * s + (0.0 if e is None else e**2)


def replicate(pred: dict, variances: dict, rng) -> dict:
    """Data drawn from the likelihood's noise model around the model values ``pred``:
    log-normal BRDF, Gaussian eta (wrapped as an axis), P and P_C.  ``pred``'s arrays are
    ``(rows,)``, or ``(draws, rows)`` for many draws at once; one standard-normal number per
    row for each term of ``variances``, in :data:`TERMS` order, draw after draw (taken in
    one call: the same numbers as one call per draw and term)."""
    terms = [t for t in TERMS if t in variances]
    shape = np.shape(pred[terms[0]])
    z = rng.standard_normal(shape[:-1] + (len(terms), shape[-1]))
    out = {}
    for k, t in enumerate(terms):
        m, e = pred[t], z[..., k, :] * np.sqrt(variances[t])
        out[t] = m * np.exp(e) if t == "brdf" else (wrap_axis(m + e) if t == "eta" else m + e)
    return out


_LOG2PI = math.log(2.0 * math.pi)


def _stokes(M, incident):
    """The Stokes vectors ``(4, ..., rows)`` of Mueller elements ``M`` ``(4, 4, ..., rows)``
    acting on the incident light: ``incident`` ``(4, rows)``, each row's Stokes vector, or
    ``(4,)``, one for every row.  The products are added in the order of the incident
    elements, as numpy's ``einsum("ab...n,bn->a...n")`` adds them (the same bits; 12 walkers x
    200 rows 31 us against einsum's 56 us, best of 5, ad hoc); one incident vector's zero
    elements are skipped (no NaN from an infinite element times 0, as einsum would give)."""
    S = M[:, 0] * incident[0]
    for b in (1, 2, 3):
        if incident.ndim == 2 or incident[b] != 0.0:
            S += M[:, b] * incident[b]
    return S


def scene_for_data(scene, data):
    """``scene`` with the detector aperture of ``data``'s sidecar, when it records one
    (the instrument that took the data decides, not the scene's default)."""
    ap = data.meta.get("aperture_deg") if data.meta else None
    if ap is None or float(ap) == scene.aperture_deg:
        return scene
    return scene.with_aperture(float(ap))


class BatchPosterior:
    """The log posterior of a likelihood with ``spec.log_prior`` and ``loglike_batch`` (this
    module's :class:`Likelihood`, the Mueller-data one): the samplers call :meth:`batch`."""

    def batch(self, U) -> np.ndarray:
        """Log posterior of positions ``U`` ``(W, k)`` in one evaluation, ``(W,)``: the prior
        (:meth:`FitSpec.log_prior`, vectorized) plus the likelihood where the prior is finite;
        ``-inf`` outside the bounds or where the likelihood is not finite."""
        U = np.atleast_2d(np.asarray(U, dtype=float))
        out = np.array(self.spec.log_prior(U), dtype=float)  # a copy: written below
        inside = np.flatnonzero(np.isfinite(out))
        if inside.size:
            ll = out[inside] + self.loglike_batch(U[inside])
            out[inside] = np.where(np.isfinite(ll), ll, -math.inf)
        return out

    def __call__(self, u) -> float:
        return float(self.batch(np.asarray(u, dtype=float)[None])[0])


class Likelihood(BatchPosterior):
    """``L(u)``: the log posterior in the spec's sampling coordinates is ``self(u)``.

    :meth:`batch` evaluates many positions at once, ``(walkers, k)`` in, ``(walkers,)`` out:
    the scene's model is evaluated once, as a model set over the walkers
    (:mod:`scatterbench.models.scene.binding`), and the prior bounds are checked once, vectorized.  A
    single position (``self(u)``, :meth:`pointwise`, :meth:`whitened`) is a batch of one, so
    every path gives the same numbers, bit for bit, whatever the batch (the chains of a
    vectorized sampler equal those of a per-walker one).  Scenes whose free keys cannot be
    bound are rebuilt per position (:meth:`model_rebuilt`, the path before model sets).

    Construction refuses, with a :class:`FitSpecError` and before any model is evaluated,
    a spec the data cannot inform: a wavelength other than the scene's, a mask that keeps
    no row, and the term problems :func:`_terms` lists.
    """

    def __init__(self, scene, spec: FitSpec, data):
        _check_wavelength(scene, data)
        self.scene = scene_for_data(scene, data)
        self.spec = spec
        self.data_all = data
        self.mask = spec.kept(data)
        self.data = data.subset(self.mask)
        d = self.data
        self._log_obs = np.log(d.brdf)
        self._same_incident = bool(np.all(d.incident == d.incident[0]))
        self._incident_rows = np.ascontiguousarray(d.incident.T)  # (4, rows): a row per Stokes element
        # the fused kernel's (polarized_kernel): one incident vector, or one per row; the data
        # by term, a term not used as zeros (not read)
        self._incident_kernel = (
            self._incident_rows[:, :1].copy() if self._same_incident else self._incident_rows
        )
        self._brdf_in = np.ascontiguousarray(d.incident[:, 0])
        zero = np.zeros(len(d))
        self._obs = np.stack(
            [self._log_obs] + [zero if getattr(d, c) is None else getattr(d, c) for c in ("eta", "P", "P_C")]
        )
        # the fitted rows, evaluated for every walker of every step: validated once
        self._rows = evaluation.FixedAngles(d.theta_i, d.theta_r, d.phi_r)
        self.terms = _terms(spec, d)
        self.n_points = len(d)
        # Whether the point source and the aperture matter (and the aperture's quadrature) is
        # decided once, at the scene's own values: re-deciding per evaluation would make ln L
        # jump where a decision flips.
        self.decisions = self.scene.decisions()
        scene_keys = {p.key: (p.low, p.high) for p in spec.free if not p.is_noise}
        probe = (d.theta_i[:8], d.theta_r[:8], d.phi_r[:8])
        self.binding = binding.bind(self.scene, scene_keys, self.decisions, probe)

    # -- model ---------------------------------------------------------------------
    def model(self, values: dict):
        """The scene's model at physical ``values`` by free key (noise levels, ``noise.*``,
        are not the model's and are ignored): scalars give one model; arrays of one shape a
        model set, trusted: callers check the prior bounds first."""
        scene = {k: v for k, v in values.items() if not k.startswith("noise.")}
        if self.binding is None:  # scalars only: the scene rebuilt
            return self.model_rebuilt({k: float(np.asarray(v).reshape(())) for k, v in scene.items()})
        shape = np.broadcast_shapes(*(np.shape(v) for v in scene.values()))
        return self.binding.values_model(scene, shape)

    def model_rebuilt(self, scene: dict):
        """The scene rebuilt and validated at scalar values of its free keys (no model set)."""
        return self.scene.with_values(scene).build(decisions=self.decisions)

    def predict(self, model, data=None, terms=None) -> dict:
        """Model ``brdf, eta, P, P_C`` at the rows of ``data`` (default: the fitted rows); a
        model set of shape ``(W, 1)`` gives ``(W, rows)`` arrays.  ``terms``: the fitted terms
        (default: all four); for ``("brdf",)``, a BRDF-only fit, only the BRDF, from the
        Mueller matrix's first row (no polarization state)."""
        d = self.data if data is None else data
        shape, M = (
            self._rows.mueller16(model) if data is None else model.mueller16(d.theta_i, d.theta_r, d.phi_r)
        )
        M = M.reshape((4, 4) + shape)
        if terms == ("brdf",):
            M = M[:1]
        if data is None:  # the fitted rows: their incident light, arranged once
            S = _stokes(M, d.incident[0] if self._same_incident else self._incident_rows)
        else:
            S = _stokes(M, np.ascontiguousarray(d.incident.T))
        if terms == ("brdf",):
            return {"brdf": S[0] / d.incident[:, 0]}
        i, eta, pc, p = ellipsometric(np.moveaxis(S, 0, -1))
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

    def _pointwise_rows(self, noise, pred) -> np.ndarray:
        """Per row, the sum over the terms of ``-(r^2 / v + ln 2 pi + ln v) / 2``, ``-inf`` where
        a term's is not finite.  The operations of that expression, in its order, each in place
        in one array per term; ``ln v`` of a variance per walker taken once per walker, not
        once per row (the same values)."""
        res = self.residuals(pred)
        var = self._variances(noise)
        total = np.zeros(res["brdf"].shape)
        with np.errstate(divide="ignore", invalid="ignore"):
            for t in self.terms:
                v = var[t]
                ll = np.square(res[t])
                ll /= v
                ll += _LOG2PI
                ll += np.log(v)
                ll *= -0.5
                np.copyto(ll, -np.inf, where=~np.isfinite(ll))
                total += ll
        return total

    def pointwise_batch(self, U) -> np.ndarray:
        """Per-row log-likelihood ``(W, rows)`` of positions ``U`` (``(W, k)``), ``-inf`` where
        impossible; positions the model refuses give rows of ``-inf``."""
        U = np.atleast_2d(np.asarray(U, dtype=float))
        if self.binding is None:
            return self._pointwise_each(U)
        v = self.spec.values(U)  # sampling coordinates -> the scene's values and the noise, once
        try:
            model = self.model(v.scene)  # one model set over the walkers
            self.binding.check(model)  # vectorized: every walker's parameters at once
        except ValueError:
            return self._pointwise_valid(U)
        return self._fused_rows(v.noise, model)

    def _fused_rows(self, noise, model):
        """:meth:`_pointwise_rows` of :meth:`predict` at the fitted rows (the reference, which
        the tests hold this to), fused in one compiled pass (:mod:`.polarized_kernel`)."""
        shape, M = self._rows.mueller16(model)
        var = self._variances(noise)
        out = np.empty(shape)
        M = np.ascontiguousarray(M.reshape(16, -1))
        loglike_rows(
            M,
            self._incident_kernel,
            self._same_incident,
            self._brdf_in,
            self._obs,
            [var.get(t) for t in TERMS],
            out,
        )
        return out

    def _pointwise_valid(self, U):
        """Rows of ``-inf`` for the positions the scene refuses (rebuilt and validated one by
        one), the others still evaluated together: a walker's value must not depend on which
        walkers share its batch (executors split the walkers differently)."""
        ok = np.zeros(len(U), dtype=bool)
        for w, u in enumerate(U):
            try:
                self.model_rebuilt(self.spec.values(u).scene)
                ok[w] = True
            except ValueError:
                continue
        out = np.full((len(U), self.n_points), -np.inf)
        if ok.all():  # refused by the binding's check only: the scene itself decides, as before
            for w, u in enumerate(U):
                out[w] = self.pointwise_rebuilt(u)
        elif ok.any():
            out[ok] = self.pointwise_batch(U[ok])
        return out

    def _pointwise_each(self, U):
        """Position by position, the scene rebuilt and validated for each (-inf where refused)."""
        out = np.full((len(U), self.n_points), -np.inf)
        for w, u in enumerate(U):
            try:
                out[w] = self.pointwise_rebuilt(u)
            except ValueError:
                continue
        return out

    def pointwise_rebuilt(self, u) -> np.ndarray:
        """Per-row log-likelihood at one position with the scene rebuilt and validated there (the
        per-walker path before model sets; a ``ValueError`` where the scene refuses ``u``)."""
        v = self.spec.values(u)
        return self._pointwise_rows(v.noise, self.predict(self.model_rebuilt(v.scene), terms=self.terms))

    def pointwise(self, u) -> np.ndarray:
        """Per-row log-likelihood (all terms summed per row), ``-inf`` where impossible."""
        return self.pointwise_batch(np.asarray(u, dtype=float)[None])[0]

    def loglike_batch(self, U) -> np.ndarray:
        """``ln L`` of positions ``U`` ``(W, k)``: :meth:`pointwise_batch` summed per row."""
        return np.sum(self.pointwise_batch(U), axis=1)

    def whitened(self, u) -> np.ndarray:
        """Residuals divided by their standard deviations (for least squares); large
        finite values where the model predicts no light."""
        v = self.spec.values(np.asarray(u, dtype=float)[None])
        res = self.residuals(self.predict(self.model(v.scene), terms=self.terms))
        var = self._variances(v.noise)
        out = []
        for t in self.terms:
            with np.errstate(divide="ignore", invalid="ignore"):
                w = (res[t] / np.sqrt(np.broadcast_to(var[t], res[t].shape)))[0]
            out.append(np.where(np.isfinite(w), w, 1e3))
        return np.concatenate(out)

    def loglike(self, u) -> float:
        return float(self.loglike_batch(np.asarray(u, dtype=float)[None])[0])

    def loglike_rebuilt(self, u) -> float:
        """``ln L`` with the scene rebuilt and validated at ``u`` (tests hold :meth:`loglike`
        to it)."""
        return float(np.sum(self.pointwise_rebuilt(u)))


#: likelihood term -> (its noise term, data attribute, its error attribute)
_TERM_DATA = {
    "brdf": ("brdf", "brdf", "brdf_err"),
    "eta": ("eta_deg", "eta", "eta_err"),
    "P": ("P", "P", "P_err"),
    "P_C": ("P_C", "P_C", "P_C_err"),
}


def _check_wavelength(scene, data):
    wl_s, wl_d = scene.wavelength_nm, data.meta.get("wavelength_nm")
    if wl_s is not None and wl_d is not None and abs(wl_s - wl_d) > 1e-9 * wl_s:
        raise FitSpecError(
            f"wavelength: the data ({wl_d:g} nm, {data.path}) and the scene ({wl_s:g} nm, {scene.path}) "
            "differ; the scene's optical constants are for its wavelength"
        )


def _terms(spec, d):
    """The likelihood's terms for the spec and the (masked) data ``d`` (see the module
    docstring).  :class:`FitSpecError` unless they give a meaningful posterior, before any
    sampling: a noise level (or error column) for the BRDF, no free noise level for a term
    the likelihood does not have (its posterior would be its prior), no term of zero
    variance (a fixed level of 0, or one whose square underflows, without an error column:
    the likelihood would be degenerate and the chain frozen)."""
    free = {p.key[6:] for p in spec.free if p.is_noise}
    have = lambda t: t in spec.noise or t in free  # noqa: E731
    if not (have("brdf") or d.brdf_err is not None):
        raise FitSpecError(
            "noise.brdf: the BRDF term needs a noise level (fixed or free: --noise brdf=0.05 or "
            "--noise brdf:0.005:1:log) or a brdf_err column"
        )
    terms = [
        t
        for t, (noise, col, err) in _TERM_DATA.items()
        if noise not in spec.off
        and getattr(d, col) is not None
        and (have(noise) or getattr(d, err) is not None)
    ]
    for t, (noise, col, err) in _TERM_DATA.items():
        if noise in free and t not in terms:
            why = "the term is off" if noise in spec.off else f"the data ({d.path}) have no {col} column"
            raise FitSpecError(
                f"noise.{noise}: free, but the likelihood has no {col} term ({why}); its posterior would be its prior"
            )
        if noise in free or t not in terms:
            continue  # a free level is sampled; a term not used has no variance
        bad = ~(np.broadcast_to(term_variances(spec.noise, d, [t])[t], (len(d),)) >= np.finfo(float).tiny)
        if bad.any():
            line = int(d.lines[bad][0]) if d.lines is not None else None
            raise FitSpecError(
                f"noise.{noise} = {spec.noise.get(noise, 0.0):g}: the {col} term has zero variance"
                + (f" at {d.path}:{line}" if line else "")
                + f" (no {err} column there): the likelihood is degenerate; give a level > 0 "
                f"(or free it: --noise {noise}:LOW:HIGH)"
            )
    return tuple(terms)
