"""Likelihood of Mueller-matrix BRDF data (:class:`~.mueller_data.MuellerData`) given a scene and
a :class:`~.mueller_spec.MuellerSpec`.

* ``m11``: Gaussian in ``ln M11`` with variance ``s_11^2 + (err_11 / M11)^2``; the model's M11 is
  multiplied by the calibration scale ``c`` (a free nuisance parameter with a log-normal prior,
  or 1).  Speckle and calibration are multiplicative, hence the log.
* every other element in ``spec.elements``: its normalized value ``M_ij / M11`` is Gaussian with
  variance ``s_ij^2 + err_ij^2`` (the calibration cancels).

The model gives ``mueller(theta_i, theta_r, phi)`` in the project's psps basis at the relative
azimuth (:func:`~.mueller_data.relative_azimuth`); each prediction is restated in the basis the
data declare with :func:`~.mueller_data.to_basis` (a fixed linear map per row, found once by
applying ``to_basis`` to the 16 unit matrices), so the noise is per element of the data as
measured.  An incidence-angle offset ``d`` makes the model's incidence ``|theta_i + d|`` (at the
opposite azimuth where ``theta_i + d < 0``: :func:`~.mueller_data.fold_negative_polar`'s rule;
the basis change is unchanged, a half-turn of the basis being the identity on Stokes vectors).

Several wavelengths are fitted at once: a scene key's value is one per row, shared, per
wavelength, from a dispersion law or from a named material, and the walkers of an emcee step
are one model set over ``(walkers, wavelengths)`` (the scene's
:mod:`~scatterbench.models.scene.binding`), validated there and gathered per row into its
models' kernels (:meth:`~scatterbench.models.base.Model.flat_mueller16_indexed`); scenes that cannot be bound
are rebuilt per walker and wavelength.  The log-likelihood omits the data-only constant ``-sum ln M11_obs``.
"""

from __future__ import annotations

import math

import numpy as np

from scatterbench.models import evaluation
from scatterbench.models.base import Sum
from scatterbench.models.scene import binding

from .fitspec import FitSpecError
from .likelihood import BatchPosterior
from .mueller_data import ELEMENTS, fold_negative_polar, to_basis
from .mueller_kernel import loglike_rows, loglike_terms, pack_map
from .mueller_spec import dispersion_index

__all__ = ["MuellerLikelihood", "Rows"]

_LOG2PI = math.log(2.0 * math.pi)


class Rows:
    """The rows of a :class:`MuellerData` as a model sees them: relative geometry, the index of
    each row's wavelength in ``wavelengths``, and the psps -> data-basis map of the elements
    ``needed`` (``{element index: [(source index, coefficient per row)]}``).

    Every per-row value of a scene key is a function of the row's wavelength alone, so a batch
    of walkers evaluates its model set per walker and distinct wavelength (``group``: each
    row's, in ``group_wavelength_nm``) and gathers by row (:meth:`index`); the angles are
    flattened over ``(walkers, rows)`` once per batch size, and the two azimuths of
    :func:`~.mueller_data.fold_negative_polar` are found here, not per batch."""

    def __init__(self, data, wavelengths, needed):
        self.data = data
        self.theta_i, self.theta_r, self.phi = data.relative_geometry()
        wl = np.asarray(wavelengths, float)
        pos = np.argmin(np.abs(data.wavelength_nm[:, None] - wl[None, :]), axis=1)
        self.wl_index = pos
        self.wavelength_nm = data.wavelength_nm
        self.group_wavelength_nm, first, group = np.unique(
            data.wavelength_nm, return_index=True, return_inverse=True
        )
        self.group = group.reshape(-1)
        self.group_wl_index = pos[first]
        # the azimuth fold_negative_polar gives each row at a positive and at a negative polar angle
        self._phi_folded = tuple(
            fold_negative_polar(np.full(len(self.phi), t), self.phi)[1] for t in (1.0, -1.0)
        )
        self.map = _basis_map(data, needed)
        self._flat = {}  # walkers: (theta_i, theta_r, phi, index), flat over (walkers, rows)

    def __len__(self):
        return len(self.theta_i)

    def _tiled(self, walkers):
        got = self._flat.get(walkers)
        if got is None:
            if len(self._flat) > 3:  # a few batch sizes in a fit; bounded for predictions
                self._flat.clear()
            G = len(self.group_wavelength_nm)
            got = [np.tile(a, walkers) for a in (self.theta_i, self.theta_r, self.phi)]
            got.append((np.arange(walkers)[:, None] * G + self.group[None, :]).reshape(-1))
            self._flat[walkers] = got
        return got

    def index(self, walkers):
        """The element of a ``(walkers, groups)`` model set (flat) that each flat
        ``(walkers, rows)`` geometry takes."""
        return self._tiled(walkers)[3]

    def angles(self, off):
        """``(theta_i, theta_r, phi)`` flat over ``(walkers, rows)`` at incidence offsets
        ``off`` ``(W, 1)`` radians (:func:`_offset`'s values; the rows' own where all are 0)."""
        ti, tr, phi, _ = self._tiled(len(off))
        if not np.any(off != 0):
            return ti, tr, phi
        s = self.theta_i[None, :] + off
        plain, turned = self._phi_folded
        return np.abs(s).reshape(-1), tr, np.where(s < 0, turned[None, :], plain[None, :]).reshape(-1)


def _basis_map(data, needed):
    """``{e: [(f, coef)]}``: element ``e`` in the data's basis is ``sum coef * M_psps[f]``."""
    n = len(data)
    T = np.empty((n, 16, 16))
    for f in range(16):
        E = np.zeros((n, 4, 4))
        E[:, f // 4, f % 4] = 1.0
        T[:, :, f] = to_basis(E, data.phi_i, data.phi_r, "psps", data.basis).reshape(n, 16)
    out = {}
    for e in needed:
        out[e] = [(f, T[:, e, f].copy()) for f in range(16) if np.any(np.abs(T[:, e, f]) > 1e-14)]
    return out


class MuellerLikelihood(BatchPosterior):
    """``self(u)``: the log posterior in the spec's sampling coordinates; :meth:`batch`
    evaluates ``(walkers, k)`` positions at once (the sampler's vectorized path)."""

    def __init__(self, scene, spec, data):
        self.spec = spec
        self.data_all = data
        self.mask = np.isin(data.wavelength_nm, spec.wavelengths)
        self.data = data.subset(self.mask)
        _check_films(scene, spec)
        self.base_scene = _fixed_materials(scene, spec)
        self.scene = _SceneView(self.base_scene, spec)
        self.elements = spec.elements
        self._e = [ELEMENTS.index(e) for e in spec.elements]
        self.rows = Rows(self.data, spec.wavelengths, sorted(set(self._e) | {0}))
        self.terms = tuple(spec.elements)
        self.n_points = len(self.data) * len(self._e)
        self._obs = _observed(self.data, self._e)
        n = len(self.data)
        src, coef, nsrc = pack_map(self.rows.map, self._e)
        obs = np.array([o for o, _ in self._obs]).reshape(len(self._e), n)
        errvar = np.array([np.broadcast_to(v, (n,)) for _, v in self._obs]).reshape(len(self._e), n)
        is_m11 = np.array([e == 0 for e in self._e])
        self._packed = (src, coef, nsrc, obs, is_m11)
        self._errvar = errvar
        self.decisions = self.base_scene.decisions()
        probe = (self.rows.theta_i[:8], self.rows.theta_r[:8], self.rows.phi[:8])
        self._bounds = _bound_keys(scene, spec)
        self.binding = binding.bind(self.base_scene, self._bounds, self.decisions, probe)

    # -- model values ----------------------------------------------------------------
    def scene_values(self, U, rows):
        """The scene keys' values at positions ``U`` ``(W, k)``: ``(W, 1)`` where shared,
        ``(W, rows)`` where they depend on the wavelength."""
        return {
            key: v if v.shape[1] == 1 else np.broadcast_to(v[:, rows.group], (len(U), len(rows)))
            for key, v in self._group_values(U, rows).items()
        }

    def _group_values(self, U, rows):
        """:meth:`scene_values` per distinct wavelength of ``rows`` (``rows.group``): ``(W, 1)``
        where shared, ``(W or 1, groups)`` where they depend on the wavelength."""
        spec, W = self.spec, len(U)
        out, per, disp = {}, {}, {}
        for i, p in enumerate(spec.free):
            x = p.from_u(U[:, i])[:, None]
            if p.role == "scene" and p.wavelength_nm is None:
                out[p.target] = x
            elif p.role == "scene":
                per.setdefault(p.target, []).append(x)
            elif p.role == "dispersion":
                disp.setdefault(p.target, []).append(x)
        for key, cols in per.items():
            out[key] = np.concatenate(cols, axis=1)[:, rows.group_wl_index]
        for key, coeffs in disp.items():
            out[key] = dispersion_index(spec.dispersion[key], coeffs, rows.group_wavelength_nm[None, :])
        for key, arr in _material_rows(spec, rows.group_wl_index).items():
            out[key] = np.broadcast_to(arr, (W, arr.shape[1]))
        return out

    def nuisance(self, U):
        """``(c, offset_rad, noise)``: calibration scale ``(W, 1)``, incidence offset ``(W, 1)``
        and the noise levels by term (``(W, 1)`` free, floats fixed)."""
        c, off, noise = np.ones((len(U), 1)), np.zeros((len(U), 1)), dict(self.spec.noise)
        for i, p in enumerate(self.spec.free):
            x = p.from_u(U[:, i])[:, None]
            if p.role == "calibration":
                c = x
            elif p.role == "offset":
                off = np.radians(x)
            elif p.role == "noise":
                noise[p.target] = x
        return c, off, noise

    def predict(self, U, rows=None):
        """Model elements at positions ``U`` and ``rows`` (default: the fitted rows), in the
        data's basis: ``{element index: (W, rows)}`` (element 0, M11, always; without the
        calibration scale).  A ``ValueError`` where the scene refuses a position."""
        rows = self.rows if rows is None else rows
        U = np.atleast_2d(np.asarray(U, dtype=float))
        return _to_data(self.predict_psps(U, rows), rows.map)

    def predict_psps(self, U, rows):
        """The model's 16 psps elements ``(16, W, rows)`` at positions ``U``: one model set over walkers x distinct wavelengths,
        validated there and gathered per row (:meth:`~scatterbench.models.base.Model.flat_mueller16_indexed`)."""
        U = np.atleast_2d(np.asarray(U, dtype=float))
        if self.binding is None:
            return self._predict_rebuilt(U, self.scene_values(U, rows), self.nuisance(U)[1], rows)
        model, index, angles = self._model_set(U, rows)
        M = np.empty((16, len(U) * len(rows)))
        _mueller16(model, index, angles, M)
        return M.reshape((16, len(U), len(rows)))

    def _model_set(self, U, rows):
        """``(model, index, angles)``: the model set over ``(walkers, wavelengths)`` at positions
        ``U``, validated, the element each flat ``(walkers, rows)`` geometry takes, and the flat
        angles (checked); a ``ValueError`` where the scene refuses a position."""
        _, off, _ = self.nuisance(U)
        W, G = len(U), len(rows.group_wavelength_nm)
        values = {k: np.broadcast_to(v, (W, G)).reshape(-1) for k, v in self._group_values(U, rows).items()}
        model = self.binding.values_model(values, (W * G,))
        self.binding.check(model)
        ti, tr, phi = rows.angles(off)
        evaluation.checked_angles(model, ti, rows.theta_r, rows.phi)  # the others: checked per row
        return model, rows.index(W), (ti, tr, phi)

    def _predict_rebuilt(self, U, values, off, rows):
        """The scene rebuilt per walker and wavelength (scenes the binding cannot express)."""
        M = np.empty((16, len(U), len(rows)))
        ti, phi = _offset(rows, off)
        for w in range(len(U)):
            for k in np.unique(rows.wl_index):
                sel = rows.wl_index == k
                at = {key: float(np.broadcast_to(v[w], (len(rows),))[sel][0]) for key, v in values.items()}
                model = self.base_scene.with_values(at).build(decisions=self.decisions)
                M[:, w, sel] = model.mueller16(
                    ti[w, sel] if ti.ndim == 2 else ti[sel],
                    rows.theta_r[sel],
                    phi[w, sel] if phi.ndim == 2 else phi[sel],
                )[1]
        return M

    # -- likelihood --------------------------------------------------------------------
    def residuals(self, U):
        """``[(residual, variance)]`` per element, each ``(W, rows)``; ``None`` where the
        scene refuses the positions."""
        try:
            P = self.predict(U)
        except ValueError:
            return None
        c, _, noise = self.nuisance(U)
        m11 = P[0]
        out = []
        with np.errstate(divide="ignore", invalid="ignore"):
            for e, (obs, err_var) in zip(self._e, self._obs, strict=True):
                s = self.spec.noise_level(ELEMENTS[e], noise)
                if e == 0:
                    r = obs - np.log(c * m11)
                else:
                    r = obs - P[e] / m11
                out.append((r, s * s + err_var))
        return out

    def pointwise_batch(self, U) -> np.ndarray:
        """Per-row log-likelihood ``(W, rows)`` (the elements summed), ``-inf`` where impossible:
        the fused kernel (:mod:`.mueller_kernel`) on the model's psps elements."""
        U = np.atleast_2d(np.asarray(U, dtype=float))
        try:
            terms = self._unit_terms(U)
            M = None if terms else self.predict_psps(U, self.rows)
        except ValueError:
            return self._pointwise_each(U)
        c, _, noise = self.nuisance(U)
        s2 = np.empty((len(self._e), len(U)))
        for k, e in enumerate(self._e):
            s2[k] = np.broadcast_to(self.spec.noise_level(ELEMENTS[e], noise), (len(U), 1))[:, 0] ** 2
        out = np.empty((len(U), len(self.data)))
        rest = (*self._packed, c[:, 0].copy(), s2, self._errvar, out)
        if terms:
            loglike_terms(*terms, *rest)
        else:
            loglike_rows(M, *rest)
        return out

    def _unit_terms(self, U):
        """``([(kernel, index)], angles)`` where the model set is a kernel's or a sum of kernels'
        with weights 1 (:func:`loglike_terms` then never holds its ``(16, W, N)`` elements), else
        ``None``; a ``ValueError`` where the scene refuses a position."""
        if self.binding is None:
            return None
        model, index, angles = self._model_set(U, self.rows)
        parts = model.terms if isinstance(model, Sum) else [(1, model)]
        if not all(_unit(w) for w, _ in parts):
            return None
        kernels = [m.indexed_kernel(index) for _, m in parts]
        return (kernels, angles) if all(kernels) else None

    def pointwise_reference(self, U) -> np.ndarray:
        """:meth:`pointwise_batch` in numpy, from :meth:`residuals` (the kernel's reference)."""
        res = self.residuals(np.atleast_2d(np.asarray(U, dtype=float)))
        total = np.zeros((len(np.atleast_2d(U)), len(self.data)))
        for r, v in res:
            with np.errstate(divide="ignore", invalid="ignore"):
                ll = -0.5 * (r * r / v + _LOG2PI + np.log(v))
            total += np.where(np.isfinite(ll), ll, -np.inf)
        return total

    def _pointwise_each(self, U):
        """Walker by walker, so that one refused position does not refuse its batch."""
        out = np.full((len(U), len(self.data)), -np.inf)
        if len(U) == 1:
            return out
        for w in range(len(U)):
            out[w] = self.pointwise_batch(U[w : w + 1])[0]
        return out

    def loglike_batch(self, U):
        return np.sum(self.pointwise_batch(U), axis=1)

    def loglike(self, u) -> float:
        return float(self.loglike_batch(np.asarray(u, float)[None])[0])

    def pointwise(self, u):
        return self.pointwise_batch(np.asarray(u, float)[None])[0]

    def whitened(self, u) -> np.ndarray:
        """Residuals over their standard deviations, every element's rows in turn (large
        finite values where the model gives no light), for least squares."""
        res = self.residuals(np.asarray(u, float)[None])
        if res is None:
            return np.full(self.n_points, 1e3)
        parts = []
        for r, v in res:
            with np.errstate(divide="ignore", invalid="ignore"):
                w = (r / np.sqrt(np.broadcast_to(v, r.shape)))[0]
            parts.append(np.where(np.isfinite(w), w, 1e3))
        return np.concatenate(parts)


def _mueller16(model, index, angles, out):
    """``out`` ``(16, N)``: ``model`` (a set, flat parameters) at flat ``angles``, geometry ``k``
    taking element ``index[k]``; a sum term by term: each term then takes its own kernel's
    long chunks, where the sum as a whole is evaluated in short chunks through numpy
    (measured: 0.34 s against 0.21 s per batch of 24 walkers x 7296 rows, one thread).  The
    terms add in place, in order, as :class:`~scatterbench.models.base.Sum` adds them; a later
    term of weight 1 is added as its kernel computes it (``flat_mueller16_indexed(add=True)``:
    the same sums, through cache-sized buffers)."""
    if not isinstance(model, Sum):
        return model.flat_mueller16_indexed(index, *angles, out)
    scratch = None
    for k, (w, m) in enumerate(model.terms):
        unit = _unit(w)
        if k and unit and not isinstance(m, Sum):
            m.flat_mueller16_indexed(index, *angles, out, add=True)
            continue
        if k and scratch is None:
            scratch = np.empty_like(out)
        term = scratch if k else out
        _mueller16(m, index, angles, term)
        if not unit:
            term *= w
        if k:
            out += term
    return out


def _unit(w) -> bool:
    """Whether a sum's weight ``w`` is the number 1 (a term added as its kernel computes it)."""
    return isinstance(w, (int, float)) and w == 1


def _to_data(M, maps):
    """``{e: (W, rows)}`` from psps elements ``M`` ``(16, W, rows)`` through the row maps."""
    out = {}
    for e, terms in maps.items():
        acc = None
        for f, coef in terms:
            t = M[f] * coef
            acc = t if acc is None else acc + t
        out[e] = acc
    return out


def _offset(rows, off):
    """Incidence ``theta_i + off`` as the data's own signed polar angles are read
    (:func:`~scatterbench.validation.fitting.mueller_data.fold_negative_polar`): ``|theta_i + off|``,
    the azimuth turned by pi where the sum is negative."""
    return fold_negative_polar(rows.theta_i[None, :] + off, rows.phi[None, :])


def _observed(data, elements):
    """``[(observed, error variance)]`` per element: ``ln M11`` and the normalized others."""
    m11 = data.mueller[:, 0, 0]
    N = data.normalized()
    out = []
    for e in elements:
        a, b = divmod(e, 4)
        err = None if data.err is None else data.err[:, a, b]
        if err is not None and not np.all(np.isnan(err)):
            err = np.where(np.isnan(err), 0.0, err)
            var = (err / m11) ** 2 if e == 0 or not data.err_normalized else err**2
        else:
            var = 0.0
        out.append((np.log(m11) if e == 0 else N[:, a, b], var))
    return out


def _material_rows(spec, wl_index):
    """``{key: (1, len(wl_index))}`` of the named materials' indices at the fitted wavelengths
    ``wl_index`` (real, imaginary parts as the key's form)."""
    out = {}
    for key, (_, table) in spec.materials.items():
        vals = np.array([table[w] for w in spec.wavelengths])[wl_index]
        if len(set(table.values())) > 1:
            if key.endswith("]"):
                out[key] = (vals.imag if key.endswith("[1]") else vals.real)[None, :]
            else:
                out[key] = vals.real[None, :]
    return out


def _check_films(scene, spec):
    """Thin films are built at the scene's wavelength: a scene with films fits its own only."""
    raw = scene.raw
    films = [
        f"[{t}.film]" for t in ("coating", "substrate") if isinstance(raw.get(t), dict) and "film" in raw[t]
    ]
    wl = scene.wavelength_nm
    if films and (len(spec.wavelengths) > 1 or wl is None or abs(spec.wavelengths[0] - wl) > 1e-9 * wl):
        raise FitSpecError(
            f"{scene.path}: {films[0]} is built at [illumination] wavelength_nm = {wl}; the fit's data are at "
            f"{', '.join(f'{w:g}' for w in spec.wavelengths)} nm: give [fit.mueller] wavelengths_nm = [{wl}]"
        )


def _fixed_materials(scene, spec):
    """The scene with each named material's index where it is one value at every fitted
    wavelength (the others are bound per row); a complex index needs the key ``[n, k]``."""
    fixed = {}
    for key, (name, table) in spec.materials.items():
        v = next(iter(table.values()))
        if not key.endswith("]") and any(abs(z.imag) > 0 for z in table.values()):
            raise FitSpecError(
                f"{scene.path}: [fit.mueller] materials {key}: {name} is absorbing (k > 0); "
                f"name {key}[0] and {key}[1] with the scene's index as [n, k]"
            )
        if len(set(table.values())) == 1:
            fixed[key] = v.imag if key.endswith("[1]") else v.real
    return scene.with_values(fixed) if fixed else scene


def _bound_keys(scene, spec):
    """``{key: (low, high)}`` of every scene key a walker or a row sets (bounds for the binding)."""
    out = {}
    for p in spec.free:
        if p.role == "scene":
            out[p.target] = (p.low, p.high)
    lam = np.asarray(spec.wavelengths, float)
    for key, law in spec.dispersion.items():
        ps = [p for p in spec.free if p.role == "dispersion" and p.target == key]
        corners = [
            dispersion_index(law, (a, b), lam)
            for a in (ps[0].low, ps[0].high)
            for b in (ps[1].low, ps[1].high)
        ]
        out[key] = (float(np.min(corners)), float(np.max(corners)))
    for key, (_, table) in spec.materials.items():
        if len(set(table.values())) > 1:
            part = [z.imag if key.endswith("[1]") else z.real for z in table.values()]
            out[key] = (min(part), max(part))
    return out


class _SceneView:
    """The scene as the optimizer's default start reads it: a per-wavelength key's value is its
    key's, a nuisance parameter's its declared start, a dispersion law's ``A`` the scene's index."""

    def __init__(self, scene, spec):
        self._scene, self._spec = scene, spec
        self.raw, self.name, self.path = scene.raw, scene.name, scene.path

    def get_value(self, key):
        p = next(p for p in self._spec.free if p.key == key)
        if p.start is not None:
            return p.start
        if p.role == "dispersion":
            return (
                float(np.real(self._scene.get_value(p.target)))
                if key.endswith("_A")
                else 0.5 * (p.low + p.high)
            )
        return self._scene.get_value(p.target)

    def describe(self):
        return self._scene.describe()
