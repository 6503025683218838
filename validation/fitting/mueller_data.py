"""Measured Mueller-matrix BRDFs: the CSV format, the reader of NIST's published file, and the
explicit conversions between conventions.

The format (``scatterbench-mueller/1``): comma separated, one header line; ``#`` lines are
comments, and two of them are keys: ``# basis: psps`` or ``# basis: xyxy`` (required, once: the
polarization basis of the elements) and ``# format: scatterbench-mueller/1`` (optional).  Blank
lines are ignored.  One row is one full Mueller-matrix BRDF at one general geometry:

====================  =========================================================================
column                meaning, allowed range
====================  =========================================================================
``theta_i_deg``       polar angle of the direction toward the source, [0, 90)
``phi_i_deg``         its azimuth in the sample frame, [-360, 360] (the standard geometry: 180)
``theta_r_deg``       polar angle of the scattered direction, [0, 90)
``phi_r_deg``         its azimuth in the sample frame, [-360, 360]
``wavelength_nm``     wavelength, [100, 20000] nm; or ``wavelength_um``, [0.1, 20] um (one of them)
``m11``               unpolarized BRDF, 1/sr, finite, > 0
``m12`` .. ``m44``    the other 15 elements, 1/sr, each within +-1.5 ``m11``; **or**
``m12/m11`` ..        the 15 normalized elements, each in [-1.5, 1.5]
``m44/m11``
``<element>_err``     optional 1-sigma uncertainty of any element column given, > 0
====================  =========================================================================

Polar angles are never negative in this format: a file that uses negative angles for the
opposite azimuth is converted with :func:`fold_negative_polar` (the NIST reader does).  The
elements are all 16 absolute ones or ``m11`` and the 15 normalized ones, never a mixture.  The
bound 1.5 on normalized elements leaves room for noise around the physical bound 1; beyond it a
value is a unit or column mistake.  A wavelength column whose values lie in the other unit's
range is refused with both ranges named (``wavelength_nm`` holding 0.532 is micrometres).  Two
rows at the same geometry and wavelength with different elements are refused (average them, or
give one with its ``_err`` columns).

NIST's published file (``PTFE.data.csv``, :func:`scatterbench.references.nist_ptfe_path`) is
read as published, recognised by its header (``lambda,thetai,phi,thetar,phir,f_r11,
f_r12/f_r11,...``): ``lambda`` in micrometres, signed polar angles (:func:`fold_negative_polar`),
elements in SCATMECH's xyxy basis (the basis of the expansion fitted to them: the measured
normalized elements agree with the expansion evaluated in xyxy, not in psps; see the
conventions guide).

Every error is a :class:`~scatterbench.validation.fitting.datafile.DataFileError` whose message
starts with ``file:line:column`` and names the column and its allowed range.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, replace
from typing import ClassVar

import numpy as np

from scatterbench.models.polarization import psps_to_xyxy, xyxy_to_psps
from scatterbench.models.text import read_utf8

from .datafile import DataFileError, split_csv

__all__ = [
    "FORMAT",
    "BASES",
    "ELEMENTS",
    "MuellerData",
    "load_mueller_data",
    "fold_negative_polar",
    "relative_azimuth",
    "to_basis",
    "normalized_to_absolute",
    "absolute_to_normalized",
    "NIST_COLUMNS",
]

FORMAT = "scatterbench-mueller/1"
BASES = ("psps", "xyxy")
#: element names, row-major: m11, m12, ..., m44
ELEMENTS = tuple(f"m{i}{j}" for i in range(1, 5) for j in range(1, 5))
_NORMALIZED = tuple(f"{e}/m11" for e in ELEMENTS[1:])
_GEOMETRY = ("theta_i_deg", "phi_i_deg", "theta_r_deg", "phi_r_deg")
#: NIST's published header, which the reader recognises
NIST_COLUMNS = ("lambda", "thetai", "phi", "thetar", "phir", "f_r11") + tuple(
    f"f_r{e[1:]}/f_r11" for e in ELEMENTS[1:]
)
#: wavelength column -> (low, high) of its unit; each range is the other's times 1000, disjoint
_WAVELENGTH = {"wavelength_nm": (100.0, 20000.0), "wavelength_um": (0.1, 20.0)}
_NORMALIZED_MAX = 1.5


def fold_negative_polar(theta, phi):
    """Signed polar angles as ``(|theta|, azimuth)``: a direction written with ``theta < 0`` lies
    at the opposite azimuth, ``(theta, phi) -> (-theta, phi + pi)``, i.e. the unit vector
    ``(sin theta cos phi, sin theta sin phi, cos theta)`` read with the sign kept.  Radians; the
    azimuth is wrapped to (-pi, pi]."""
    theta, phi = np.broadcast_arrays(np.asarray(theta, float), np.asarray(phi, float))
    return np.abs(theta), _wrap(np.where(theta < 0, phi + math.pi, phi))


def relative_azimuth(phi_i, phi_r):
    """The scattering azimuth of the project's standard geometry (source at azimuth pi),
    ``phi_r - phi_i + pi`` wrapped to (-pi, pi], from the sample-frame azimuths of the direction
    toward the source (``phi_i``) and of the scattered direction (``phi_r``).  For an isotropic
    sample this is all the azimuthal information there is: ``model.mueller(theta_i, theta_r,
    relative_azimuth(phi_i, phi_r))``."""
    return _wrap(np.asarray(phi_r, float) - np.asarray(phi_i, float) + math.pi)


def _wrap(a):
    """Angles wrapped to (-pi, pi]."""
    return math.pi - np.mod(math.pi - np.asarray(a, float), 2.0 * math.pi)


def to_basis(M, phi_i, phi_r, source, target):
    """Mueller matrices ``(..., 4, 4)`` restated from basis ``source`` to ``target`` (``"psps"`` or
    ``"xyxy"``): ``M_psps = R(-phi_r) M_xyxy R(-phi_i)`` and its inverse
    (:func:`scatterbench.models.polarization.xyxy_to_psps`), sample-frame azimuths in radians."""
    for name, b in (("source", source), ("target", target)):
        if b not in BASES:
            raise ValueError(f"{name} basis must be one of {BASES}; got {b!r}")
    if source == target:
        return np.array(M, dtype=float)
    convert = xyxy_to_psps if source == "xyxy" else psps_to_xyxy
    return convert(M, phi_i, phi_r)


def normalized_to_absolute(m11, normalized):
    """Absolute elements ``M = m11 N`` from ``m11`` ``(...)`` and normalized elements ``N``
    ``(..., 4, 4)`` (``N[..., 0, 0]`` is taken as 1 whatever it holds)."""
    N = np.array(normalized, dtype=float)
    N[..., 0, 0] = 1.0
    return np.asarray(m11, float)[..., None, None] * N


def absolute_to_normalized(M):
    """``(m11, N)``: ``m11 = M[..., 0, 0]`` and ``N = M / m11`` (``N[..., 0, 0] = 1``)."""
    M = np.asarray(M, dtype=float)
    m11 = M[..., 0, 0]
    return m11, M / m11[..., None, None]


@dataclass
class MuellerData:
    """Measured Mueller-matrix BRDFs, angles in radians (sample frame, polar angles >= 0).

    ``mueller`` holds the absolute elements (1/sr) in ``basis``.  ``err``, when given, holds the
    1-sigma uncertainties as the file gave them: of ``m11`` (1/sr) and of the other elements,
    absolute or, with ``err_normalized``, of the normalized ones; NaN where not given.
    """

    path: str
    theta_i: np.ndarray
    phi_i: np.ndarray  # azimuth of the direction toward the source
    theta_r: np.ndarray
    phi_r: np.ndarray
    wavelength_nm: np.ndarray
    mueller: np.ndarray  # (N, 4, 4)
    basis: str
    err: np.ndarray | None = None  # (N, 4, 4)
    err_normalized: bool = False
    lines: np.ndarray | None = None
    meta: dict = field(default_factory=dict)

    #: every per-row array, by name (what a fit's fingerprint hashes)
    _ARRAYS: ClassVar[tuple] = (
        "theta_i",
        "phi_i",
        "theta_r",
        "phi_r",
        "wavelength_nm",
        "mueller",
        "err",
        "lines",
    )

    def __len__(self):
        return len(self.theta_i)

    def normalized(self) -> np.ndarray:
        """``M / M11`` ``(N, 4, 4)``."""
        return absolute_to_normalized(self.mueller)[1]

    def relative_geometry(self):
        """``(theta_i, theta_r, phi_r)`` of the project's standard geometry, for an isotropic
        sample (:func:`relative_azimuth`)."""
        return self.theta_i, self.theta_r, relative_azimuth(self.phi_i, self.phi_r)

    def in_basis(self, basis) -> MuellerData:
        """The same data with the elements restated in ``basis`` (:func:`to_basis`).  The
        uncertainties are not carried over a basis change (they would need the covariances)."""
        if basis == self.basis:
            return self
        M = to_basis(self.mueller, self.phi_i, self.phi_r, self.basis, basis)
        return replace(self, mueller=M, basis=basis, err=None, err_normalized=False)

    def subset(self, keep) -> MuellerData:
        """The rows ``keep`` selects (a boolean mask or an index array)."""
        return replace(
            self, **{a: None if getattr(self, a) is None else getattr(self, a)[keep] for a in self._ARRAYS}
        )


# ----------------------------------------------------------------------------- reading
def _split(path, text):
    """``(keys, header, header_line, rows)``: the ``# key: value`` lines, the first other
    non-comment line and the ``(line, fields)`` after it."""
    keys = {}
    header, header_line, rows = split_csv(
        path, text.splitlines(), comment=lambda lineno, line: _header_key(path, lineno, line, keys)
    )
    return keys, header, header_line, rows


def _header_key(path, lineno, line, keys):
    """Record a ``# basis: ...`` or ``# format: ...`` line (other comments are free text)."""
    m = re.match(r"\s*#\s*(basis|format)\s*:\s*(.*?)\s*$", line)
    if not m:
        return
    key, value = m.group(1), m.group(2)
    col = line.index(value) + 1 if value else len(line) + 1
    if key in keys:
        raise DataFileError(path, lineno, col, f"'{key}' given twice (first on line {keys[key][1]})")
    if key == "basis" and value not in BASES:
        raise DataFileError(path, lineno, col, f"basis must be one of {', '.join(BASES)}; got {value!r}")
    if key == "format" and value != FORMAT:
        raise DataFileError(path, lineno, col, f"format must be {FORMAT!r}; got {value!r}")
    keys[key] = (value, lineno)


def _columns(path, header, line):
    """``(col_of, form, wavelength column)``: each name's 1-based position, checked complete."""
    col_of = {}
    for j, name in enumerate(header, 1):
        if name in col_of:
            raise DataFileError(path, line, j, f"column {name!r} appears twice")
        col_of[name] = j
    wl = [c for c in _WAVELENGTH if c in col_of]
    if len(wl) != 1:
        what = "both" if wl else "neither"
        raise DataFileError(
            path, line, None, f"give one wavelength column, wavelength_nm or wavelength_um ({what} found)"
        )
    missing = [c for c in _GEOMETRY + ("m11",) if c not in col_of]
    if missing:
        raise DataFileError(path, line, None, f"missing column(s) {', '.join(missing)}")
    form = _element_form(path, line, col_of)
    elements = ("m11",) + (ELEMENTS[1:] if form == "absolute" else _NORMALIZED)
    allowed = set(_GEOMETRY) | {wl[0]} | set(elements) | {f"{e}_err" for e in elements}
    for name, j in col_of.items():
        if name not in allowed:
            hint = f" ({name}_err needs column {name[:-4]!r})" if name.endswith("_err") else ""
            raise DataFileError(path, line, j, f"unknown column {name!r}{hint}")
    return col_of, form, wl[0]


def _element_form(path, line, col_of):
    """``"absolute"`` (m12..m44) or ``"normalized"`` (m12/m11..m44/m11), complete and unmixed."""
    absolute = [e for e in ELEMENTS[1:] if e in col_of]
    normalized = [e for e in _NORMALIZED if e in col_of]
    if absolute and normalized:
        raise DataFileError(
            path,
            line,
            col_of[normalized[0]],
            "give the elements as m12..m44 OR as m12/m11..m44/m11, not both",
        )
    form, have, names = (
        ("absolute", absolute, ELEMENTS[1:]) if absolute else ("normalized", normalized, _NORMALIZED)
    )
    if len(have) != 15:
        missing = [e for e in names if e not in col_of]
        raise DataFileError(
            path,
            line,
            None,
            f"incomplete Mueller matrix: missing column(s) {', '.join(missing)} (all 16 elements needed)",
        )
    return form


def _numbers(path, header, rows):
    """The data rows as a float array ``(N, columns)``; a wrong field count or a cell that is not
    a finite number is an error at its line and column."""
    out = np.empty((len(rows), len(header)))
    for r, (lineno, fields) in enumerate(rows):
        if len(fields) != len(header):
            col = min(len(fields), len(header)) + 1
            raise DataFileError(
                path, lineno, col, f"expected {len(header)} fields (the header's), found {len(fields)}"
            )
        try:
            out[r] = [float(f) for f in fields]
        except ValueError:
            out[r] = np.nan
        if not np.all(np.isfinite(out[r])):
            j = next(j for j, f in enumerate(fields) if not _is_finite(f))
            raise DataFileError(
                path, lineno, j + 1, f"column {header[j]!r}: not a finite number: {fields[j].strip()!r}"
            )
    return out


def _is_finite(text):
    try:
        return math.isfinite(float(text))
    except ValueError:
        return False


def _first_bad(path, rows, header, values, bad, message):
    """Raise for the first ``True`` of ``bad`` ``(N, columns)`` in file order: ``message(name, value)``."""
    if not np.any(bad):
        return
    r, j = np.unravel_index(np.argmax(bad), bad.shape)
    raise DataFileError(path, rows[r][0], j + 1, message(header[j], values[r, j]))


def _check_ranges(path, rows, header, values, col_of, wl):
    """Every value in its column's range, the first violation in file order reported."""
    names = np.array(header)
    polar = np.isin(names, ["theta_i_deg", "theta_r_deg"])
    azimuth = np.isin(names, ["phi_i_deg", "phi_r_deg"])
    _first_bad(
        path,
        rows,
        header,
        values,
        polar & ((values < 0) | (values >= 90)),
        lambda n, v: (
            f"column {n!r}: {v:g} is outside [0, 90) (a negative polar angle is "
            "the opposite azimuth: convert it with fold_negative_polar)"
        ),
    )
    _first_bad(
        path,
        rows,
        header,
        values,
        azimuth & (np.abs(values) > 360),
        lambda n, v: f"column {n!r}: {v:g} is outside [-360, 360]",
    )
    _check_wavelength(path, rows, values[:, col_of[wl] - 1], wl, col_of[wl])
    m11 = values[:, col_of["m11"] - 1]
    _first_bad(
        path,
        rows,
        header,
        values,
        (names == "m11") & (values <= 0),
        lambda n, v: f"column 'm11': {v:g} is not > 0 (the unpolarized BRDF, 1/sr)",
    )
    errs = np.char.endswith(names.astype(str), "_err")
    _first_bad(
        path,
        rows,
        header,
        values,
        errs & (values <= 0),
        lambda n, v: f"column {n!r}: {v:g} is not > 0 (a 1-sigma uncertainty)",
    )
    normalized = np.isin(names, _NORMALIZED)
    _first_bad(
        path,
        rows,
        header,
        values,
        normalized & (np.abs(values) > _NORMALIZED_MAX),
        lambda n, v: f"column {n!r}: {v:g} is outside [-1.5, 1.5] (a normalized element)",
    )
    absolute = np.isin(names, ELEMENTS[1:])
    _first_bad(
        path,
        rows,
        header,
        values,
        absolute & (np.abs(values) > _NORMALIZED_MAX * m11[:, None]),
        lambda n, v: f"column {n!r}: {v:g} is beyond +-1.5 m11 (|{n}/m11| <= 1.5 allowed)",
    )


def _check_wavelength(path, rows, wl, column, col, name=None):
    """The wavelength column's values in its unit's range; values in the other unit's range are
    named as such (a column named for nm that holds micrometres, or the reverse).  ``col``: its
    1-based position; ``name``: the file's own name for it (NIST's ``lambda``, in um)."""
    lo, hi = _WAVELENGTH[column]
    bad = (wl < lo) | (wl > hi)
    if not np.any(bad):
        return
    r = int(np.argmax(bad))
    other = "wavelength_um" if column == "wavelength_nm" else "wavelength_nm"
    olo, ohi = _WAVELENGTH[other]
    unit, ounit = column[-2:], other[-2:]
    if olo <= wl[r] <= ohi:
        fix = f"name the column {other}, or " if name is None else ""
        why = f"{wl[r]:g} is outside [{lo:g}, {hi:g}] {unit} and looks like {ounit}: {fix}give the values in {unit}"
    else:
        why = f"{wl[r]:g} is outside [{lo:g}, {hi:g}] {unit}"
    raise DataFileError(path, rows[r][0], col, f"column {name or column!r}: {why}")


def _check_duplicates(path, rows, geometry, mueller):
    """Rows at one geometry and wavelength (azimuths modulo 360, angles to 1e-9 deg) must agree."""
    key = np.column_stack(
        [
            geometry[:, 0],
            np.mod(geometry[:, 1], 360.0),
            geometry[:, 2],
            np.mod(geometry[:, 3], 360.0),
            geometry[:, 4],
        ]
    )
    _, first, inverse = np.unique(np.round(key, 9), axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    ref = first[inverse]  # the first row of each row's geometry
    flat = mueller.reshape(len(mueller), -1)
    scale = np.abs(flat[:, :1]) + np.abs(flat[ref, :1])
    conflict = (ref != np.arange(len(rows))) & np.any(np.abs(flat - flat[ref]) > 1e-12 * scale, axis=1)
    if np.any(conflict):
        r = int(np.argmax(conflict))
        raise DataFileError(
            path,
            rows[r][0],
            None,
            f"same geometry and wavelength as line {rows[ref[r]][0]} with different "
            "elements: average repeated measurements into one row (with _err columns)",
        )


def load_mueller_data(path) -> MuellerData:
    """Read a Mueller-BRDF data file: the ``scatterbench-mueller/1`` format or NIST's published
    ``PTFE.data.csv`` (recognised by its header).

    Raises
    ------
    DataFileError
        Any problem, its message starting with ``file:line:column``.
    """
    path = str(path)
    text = read_utf8(path, "data file", lambda at, msg: DataFileError(path, *(at or (0, None)), msg))
    keys, header, header_line, rows = _split(path, text)
    if tuple(header) == NIST_COLUMNS:
        return _nist(path, header, header_line, rows)
    if tuple(header[:6]) == NIST_COLUMNS[:6]:  # NIST's columns, but not all of them
        missing = [c for c in NIST_COLUMNS if c not in header]
        extra = [c for c in header if c not in NIST_COLUMNS]
        raise DataFileError(
            path,
            header_line,
            None,
            "NIST's columns, incomplete or changed: "
            + (f"missing {', '.join(missing)}" if missing else f"unknown {', '.join(extra)}")
            + f" (NIST's PTFE.data.csv has the 21 columns {','.join(NIST_COLUMNS)}, in that order)",
        )
    col_of, form, wl = _columns(path, header, header_line)
    if "basis" not in keys:
        raise DataFileError(
            path, header_line, None, "missing '# basis: psps' or '# basis: xyxy' line before the header"
        )
    if not rows:
        raise DataFileError(path, header_line, None, "no data rows")
    values = _numbers(path, header, rows)
    _check_ranges(path, rows, header, values, col_of, wl)
    col = {name: values[:, j - 1] for name, j in col_of.items()}
    names = ELEMENTS[1:] if form == "absolute" else _NORMALIZED
    M = np.stack([col["m11"]] + [col[n] for n in names], axis=-1).reshape(-1, 4, 4)
    if form == "normalized":
        M = normalized_to_absolute(col["m11"], M)
    wl_nm = col[wl] * (1000.0 if wl == "wavelength_um" else 1.0)
    geometry = np.column_stack([col[g] for g in _GEOMETRY] + [wl_nm])
    _check_duplicates(path, rows, geometry, M)
    err = None
    if any(name.endswith("_err") for name in col_of):
        err = np.stack([col.get(f"{n}_err", np.full(len(rows), np.nan)) for n in ("m11",) + names], -1)
        err = err.reshape(-1, 4, 4)
    return MuellerData(
        path=path,
        theta_i=np.radians(col["theta_i_deg"]),
        phi_i=np.radians(col["phi_i_deg"]),
        theta_r=np.radians(col["theta_r_deg"]),
        phi_r=np.radians(col["phi_r_deg"]),
        wavelength_nm=wl_nm,
        mueller=M,
        basis=keys["basis"][0],
        err=err,
        err_normalized=form == "normalized",
        lines=np.array([ln for ln, _ in rows]),
        meta={k: v for k, (v, _) in keys.items()},
    )


def _nist(path, header, header_line, rows):
    """NIST's ``PTFE.data.csv`` as published: lambda (um), signed polar angles (deg), f_r11 and
    the 15 normalized elements, xyxy basis.  The same range checks as the format's, on NIST's
    own columns."""
    if not rows:
        raise DataFileError(path, header_line, None, "no data rows")
    values = _numbers(path, header, rows)
    names = np.array(header)
    angle = np.isin(names, ["thetai", "thetar"])
    _first_bad(
        path,
        rows,
        header,
        values,
        angle & (np.abs(values) >= 90),
        lambda n, v: f"column {n!r}: {v:g} is outside (-90, 90) (signed polar angle, degrees)",
    )
    _first_bad(
        path,
        rows,
        header,
        values,
        np.isin(names, ["phi", "phir"]) & (np.abs(values) > 360),
        lambda n, v: f"column {n!r}: {v:g} is outside [-360, 360]",
    )
    _check_wavelength(path, rows, values[:, 0], "wavelength_um", 1, name="lambda")
    _first_bad(
        path,
        rows,
        header,
        values,
        (names == "f_r11") & (values <= 0),
        lambda n, v: f"column 'f_r11': {v:g} is not > 0 (the unpolarized BRDF, 1/sr)",
    )
    _first_bad(
        path,
        rows,
        header,
        values,
        (np.arange(len(header)) > 5) & (np.abs(values) > _NORMALIZED_MAX),
        lambda n, v: f"column {n!r}: {v:g} is outside [-1.5, 1.5] (a normalized element)",
    )
    ti, phi_i = fold_negative_polar(np.radians(values[:, 1]), np.radians(values[:, 2]))
    tr, phi_r = fold_negative_polar(np.radians(values[:, 3]), np.radians(values[:, 4]))
    N = np.concatenate([np.ones((len(rows), 1)), values[:, 6:]], axis=1).reshape(-1, 4, 4)
    M = normalized_to_absolute(values[:, 5], N)
    wl_nm = values[:, 0] * 1000.0
    geometry = np.degrees(np.column_stack([ti, phi_i, tr, phi_r]))
    _check_duplicates(path, rows, np.column_stack([geometry, wl_nm]), M)
    return MuellerData(
        path=path,
        theta_i=ti,
        phi_i=phi_i,
        theta_r=tr,
        phi_r=phi_r,
        wavelength_nm=wl_nm,
        mueller=M,
        basis="xyxy",
        lines=np.array([ln for ln, _ in rows]),
        meta={"format": "NIST PTFE.data.csv"},
    )
