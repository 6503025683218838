"""Measured polarized BRDF data: the CSV format, its JSON sidecar, and a strict loader.

CSV (comma separated, one header line; lines starting with ``#`` are comments,
e.g. provenance; blank lines are ignored).  Angles are in DEGREES and say so in
the column name; the geometry is SCATMECH's (DESIGN.md): specular is
``theta_r = theta_i, phi_r = 0``, in-plane backscatter is ``phi_r = 180``.

=================  ========  ===============================================
column             required  meaning, allowed range
=================  ========  ===============================================
``theta_i_deg``    yes       incidence polar angle, [0, 90)
``theta_r_deg``    yes       scattering polar angle, [0, 90)
``phi_r_deg``      yes       scattering azimuth, [-360, 360]
``brdf``           yes       BRDF for the incident state, 1/sr, finite, > 0
``brdf_err``       no        1-sigma absolute uncertainty of ``brdf``, > 0
``s1,s2,s3``       no        scattered Stokes vector normalized by I
                             (``Q/I, U/I, V/I``, ``Q = I_s - I_p``), each in
                             [-1.5, 1.5]; all three or none
``eta_deg``        no        principal angle of polarization, [-90, 90]
``P``              no        degree of polarization, [-0.5, 1.5]
``P_C``            no        degree of circular polarization, [-1.5, 1.5]
``eta_err_deg``,   no        1-sigma uncertainties of those, > 0
``P_err``,
``P_C_err``
``incident``       see       incident polarization of the row: a name of
                   below     ``models.polarization.stokes`` (``unpolarized``,
                             ``s``, ``p``, ``+45``, ``-45``, ``left``,
                             ``right``, ``linear:<deg>``)
=================  ========  ===============================================

``s1..s3`` and ``eta_deg/P/P_C`` are two spellings of the same thing: give one
of them, not both.  Degrees of polarization above 1 are allowed up to 1.5
because a noisy measurement of a fully polarized beam scatters around 1, and
``P`` down to -0.5 because, in the same additive noise model the likelihood
uses, a nearly depolarized beam's estimate scatters around 0; values beyond
are rejected (a percent value given as a fraction's column, say).

Sidecar: ``NAME.json`` beside ``NAME.csv`` (optional), an object with the keys
``format`` (``"scatterbench-brdf/1"``), ``sample``, ``instrument``,
``description`` (strings), ``wavelength_nm`` (> 0), ``aperture_deg`` (full
angle, [0, 90]), ``incident_polarization`` (as the ``incident`` column, for
every row), ``provenance`` (any JSON) and ``truth`` (for synthetic data: the
true values by scene key).  Unknown keys are errors.  The incident polarization
must be given exactly once (column or sidecar): the loader never assumes
unpolarized light.

Every error is a :class:`DataFileError` whose message starts with
``file:line:column`` and names the column and the allowed range.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import re
from dataclasses import dataclass, field

import numpy as np

from scatterbench.models.constraints import interval_notation
from scatterbench.models.polarization import ellipsometric, stokes
from scatterbench.models.text import is_number, long_digits, read_utf8, shown, where
from scatterbench.validation.atomic import atomic_write_json, atomic_write_text

__all__ = ["DataFileError", "Dataset", "load_data", "write_data", "COLUMNS", "SIDECAR_KEYS"]

FORMAT = "scatterbench-brdf/1"

#: column name -> (low, high, low_open, high_open, required)
COLUMNS = {
    "theta_i_deg": (0.0, 90.0, False, True, True),
    "theta_r_deg": (0.0, 90.0, False, True, True),
    "phi_r_deg": (-360.0, 360.0, False, False, True),
    "brdf": (0.0, math.inf, True, True, True),
    "brdf_err": (0.0, math.inf, True, True, False),
    "s1": (-1.5, 1.5, False, False, False),
    "s2": (-1.5, 1.5, False, False, False),
    "s3": (-1.5, 1.5, False, False, False),
    "eta_deg": (-90.0, 90.0, False, False, False),
    "P": (-0.5, 1.5, False, False, False),
    "P_C": (-1.5, 1.5, False, False, False),
    "eta_err_deg": (0.0, math.inf, True, True, False),
    "P_err": (0.0, math.inf, True, True, False),
    "P_C_err": (0.0, math.inf, True, True, False),
}
TEXT_COLUMNS = {"incident"}
SIDECAR_KEYS = {
    "format",
    "sample",
    "instrument",
    "description",
    "wavelength_nm",
    "aperture_deg",
    "incident_polarization",
    "provenance",
    "truth",
}


class DataFileError(ValueError):
    """A data-file problem; the message starts with ``file:line:column``."""

    def __init__(self, path, line, column, message):
        self.path, self.line, self.column = path, line, column
        where = f"{path}:{line}" + (f":{column}" if column is not None else "")
        super().__init__(f"{where}: {message}")


@dataclass
class Dataset:
    """Loaded data, angles in radians (API convention).  Optional quantities are ``None``."""

    path: str
    theta_i: np.ndarray
    theta_r: np.ndarray
    phi_r: np.ndarray
    brdf: np.ndarray
    incident: np.ndarray  # (N, 4) unit-intensity Stokes vectors
    brdf_err: np.ndarray | None = None
    eta: np.ndarray | None = None  # radians
    P: np.ndarray | None = None
    P_C: np.ndarray | None = None
    eta_err: np.ndarray | None = None  # radians
    P_err: np.ndarray | None = None
    P_C_err: np.ndarray | None = None
    lines: np.ndarray | None = None  # source line of each row
    meta: dict = field(default_factory=dict)

    def __len__(self):
        return len(self.brdf)

    _ARRAYS = (
        "theta_i",
        "theta_r",
        "phi_r",
        "brdf",
        "incident",
        "brdf_err",
        "eta",
        "P",
        "P_C",
        "eta_err",
        "P_err",
        "P_C_err",
        "lines",
    )

    def subset(self, keep) -> Dataset:
        """The rows where the boolean mask (or index array) ``keep`` selects."""
        kw = {}
        for name in self._ARRAYS:
            v = getattr(self, name)
            kw[name] = None if v is None else np.asarray(v)[keep]
        return Dataset(path=self.path, meta=dict(self.meta), **kw)

    def replace(self, **changes) -> Dataset:
        path = changes.pop("path", self.path)
        kw = {name: getattr(self, name) for name in self._ARRAYS}
        kw.update(changes)
        return Dataset(path=path, meta=dict(self.meta), **kw)


def _sidecar_path(path):
    return os.path.splitext(path)[0] + ".json"


def _text_of(path, what):
    """The UTF-8 text of a file (a byte-order mark dropped); errors name ``file:line:column``."""
    return read_utf8(path, what, lambda at, msg: DataFileError(path, *(at or (0, None)), msg))


class _NotJSON(ValueError):
    """A token JSON does not have (NaN, Infinity) or a key given twice; ``pattern`` finds
    it in the text (the parser does not say where)."""

    def __init__(self, message, pattern):
        super().__init__(message)
        self.pattern = pattern


def _no_constants(token):
    raise _NotJSON(f"{token} is not a JSON number (write null, or leave the key out)", re.escape(token))


def _no_duplicates(pairs):
    keys = [k for k, _ in pairs]
    for k in keys:
        if keys.count(k) > 1:
            raise _NotJSON(f"key {k!r} given twice", re.escape(json.dumps(k)))
    return dict(pairs)


def _parse_json(side, text):
    """The sidecar's JSON value: strict (no NaN/Infinity, no key twice), errors located."""
    try:
        return json.loads(text, parse_constant=_no_constants, object_pairs_hook=_no_duplicates)
    except json.JSONDecodeError as exc:
        raise DataFileError(side, exc.lineno, exc.colno, f"not valid JSON: {exc.msg}") from exc
    except RecursionError as exc:
        raise DataFileError(side, 1, None, "not valid JSON for a sidecar: nested too deeply") from exc
    except ValueError as exc:  # _NotJSON, or an integer of thousands of digits Python will not read
        if isinstance(exc, _NotJSON):
            found = list(re.finditer(exc.pattern, text))
            at = found[-1].start() if found else 0
        else:
            digits = long_digits(text)
            at = digits.start() if digits else 0
        line, col = where(text, at)
        keys = re.findall(r'"((?:[^"\\]|\\.)*)"\s*:', text[:at])  # the key the token belongs to
        key = f"{keys[-1]}: " if keys and "twice" not in str(exc) else ""
        raise DataFileError(side, line, col, f"{key}not valid JSON: {exc}") from exc


def _load_sidecar(path):
    side = _sidecar_path(path)
    if not os.path.exists(side):
        return {}, None
    text = _text_of(side, "sidecar")
    meta = _parse_json(side, text)
    if not isinstance(meta, dict):
        raise DataFileError(side, 1, 1, "the sidecar must be a JSON object")

    def line_of(key):
        for i, ln in enumerate(text.splitlines(), 1):
            col = ln.find(f'"{key}"')
            if col >= 0:
                return i, col + 1
        return 1, None

    for key, value in meta.items():
        problem = _sidecar_problem(key, value)
        if problem:
            raise DataFileError(side, *line_of(key), problem)
    return meta, side


def _sidecar_problem(key, value):
    """What is wrong with a sidecar entry (None: nothing)."""
    if key not in SIDECAR_KEYS:
        return f"unknown key {key!r}; allowed: {', '.join(sorted(SIDECAR_KEYS))}"
    if key == "format" and value != FORMAT:
        return f"format must be {FORMAT!r}; got {shown(value)}"
    if key in ("sample", "instrument", "description") and not isinstance(value, str):
        return f"{key} must be a string; got {shown(value)}"
    if key == "wavelength_nm" and not (is_number(value) and value > 0):
        return f"wavelength_nm must be a finite number > 0; got {shown(value)}"
    if key == "aperture_deg" and not (is_number(value) and 0 <= value <= 90):
        return f"aperture_deg must be a number in [0, 90]; got {shown(value)}"
    if key == "incident_polarization":
        try:
            stokes(value)
        except ValueError as exc:
            return f"incident_polarization: {exc}"
    if key == "truth":
        if not isinstance(value, dict):
            return "truth must be an object {scene key: value}"
        for k, v in value.items():
            if not is_number(v):
                return f"truth: {k}: must be a finite number (the true value); got {shown(v)}"
    return None


def _read_lines(path):
    return _text_of(path, "data file").splitlines()


def split_csv(path, raw_lines, comment=None):
    """``(header, header_line, rows)``: the first non-comment line and the ``(line, fields)`` after
    it; ``comment(lineno, line)`` is called for each comment line (``#``), if given (the Mueller
    files' ``# key: value`` lines)."""
    header, header_line, rows = None, None, []
    for lineno, text in enumerate(raw_lines, 1):
        stripped = text.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            if comment is not None:
                comment(lineno, text)
            continue
        try:
            fields = next(csv.reader([text]))
        except csv.Error as exc:  # a NUL byte, a field beyond the csv module's size limit
            raise DataFileError(path, lineno, None, f"not a CSV line ({exc})") from exc
        if header is None:
            header, header_line = [f.strip() for f in fields], lineno
        else:
            rows.append((lineno, fields))
    if header is None:
        raise DataFileError(path, len(raw_lines) or 1, None, "no header line (and no data)")
    return header, header_line, rows


def _columns(path, header, line):
    """Column name -> 1-based position; every name known, none twice, the required ones present."""
    known = set(COLUMNS) | TEXT_COLUMNS
    col_of = {}
    for j, name in enumerate(header, 1):
        if name in col_of:
            raise DataFileError(path, line, j, f"column {name!r} appears twice")
        if name not in known:
            hint = ""
            if name in ("theta_i", "theta_r", "phi_r", "eta", "eta_err"):
                hint = f" (angles are in degrees in a column named {name}_deg)"
            raise DataFileError(
                path,
                line,
                j,
                f"unknown column {name!r}{hint}; allowed: {', '.join(list(COLUMNS) + ['incident'])}",
            )
        col_of[name] = j
    for name, (*_, required) in COLUMNS.items():
        if required and name not in col_of:
            raise DataFileError(path, line, None, f"missing required column {name!r}")
    return col_of


def _check_polarization_columns(path, line, col_of):
    """s1..s3 complete, or eta_deg/P/P_C, not both; error columns only beside their quantity."""
    have_s = [c for c in ("s1", "s2", "s3") if c in col_of]
    if have_s and len(have_s) != 3:
        missing = sorted({"s1", "s2", "s3"} - set(have_s))
        raise DataFileError(
            path, line, None, f"missing column(s) {', '.join(missing)}: give s1, s2, s3 together"
        )
    have_e = [c for c in ("eta_deg", "P", "P_C") if c in col_of]
    if have_s and have_e:
        raise DataFileError(
            path,
            line,
            col_of[have_e[0]],
            "give the polarization as s1, s2, s3 OR as eta_deg, P, P_C, not both",
        )
    for err, base in (("eta_err_deg", "eta_deg"), ("P_err", "P"), ("P_C_err", "P_C")):
        if err in col_of and base not in col_of:
            raise DataFileError(path, line, col_of[err], f"column {err!r} needs column {base!r}")


def _check_incident_given_once(path, line, col_of, meta, side):
    if "incident" in col_of and "incident_polarization" in meta:
        raise DataFileError(
            path,
            line,
            col_of["incident"],
            f"incident polarization given twice (column and {side}); give it once",
        )
    if "incident" not in col_of and "incident_polarization" not in meta:
        raise DataFileError(
            path,
            line,
            None,
            "missing column 'incident' (the incident polarization, e.g. linear:45 or unpolarized); "
            "or set incident_polarization in the JSON sidecar",
        )


def _number(path, lineno, j, name, cell):
    """The cell of numeric column ``name`` as a float inside the column's range."""
    lo, hi, lo_open, hi_open, _ = COLUMNS[name]
    if cell == "":
        raise DataFileError(path, lineno, j, f"column {name!r}: missing value")
    try:
        x = float(cell)
    except ValueError:
        raise DataFileError(path, lineno, j, f"column {name!r}: not a number: {cell!r}") from None
    if not math.isfinite(x):
        raise DataFileError(path, lineno, j, f"column {name!r}: {cell!r} is not a finite number")
    if x < lo or x > hi or (lo_open and x == lo) or (hi_open and x == hi):
        raise DataFileError(
            path,
            lineno,
            j,
            f"column {name!r}: {x:g} is outside {interval_notation(lo, hi, lo_open, hi_open)}",
        )
    return x


def _parse_rows(path, header, rows, col_of):
    """``(values by numeric column, incident Stokes vectors)`` of the data rows."""
    values = {name: np.empty(len(rows)) for name in col_of if name in COLUMNS}
    incident = np.empty((len(rows), 4))
    cache = {}
    for i, (lineno, fields) in enumerate(rows):
        if len(fields) != len(header):
            col = min(len(fields), len(header)) + 1
            raise DataFileError(
                path, lineno, col, f"expected {len(header)} fields (the header's), found {len(fields)}"
            )
        for name, j in col_of.items():
            cell = fields[j - 1].strip()
            if name != "incident":
                values[name][i] = _number(path, lineno, j, name, cell)
                continue
            if cell not in cache:
                try:
                    cache[cell] = stokes(cell)
                except ValueError as exc:
                    raise DataFileError(path, lineno, j, f"column 'incident': {exc}") from exc
            incident[i] = cache[cell]
    return values, incident


def _ellipsometric(values, n):
    """``(eta, P, P_C)`` in radians from s1..s3 or eta_deg/P/P_C (``None`` where absent)."""
    if "s1" in values:
        s = np.stack([np.ones(n), values["s1"], values["s2"], values["s3"]], axis=-1)
        _, eta, pc, p = ellipsometric(s)
        return eta, p, pc
    eta = np.radians(values["eta_deg"]) if "eta_deg" in values else None
    return eta, values.get("P"), values.get("P_C")


def load_data(path) -> Dataset:
    """Read and validate a data file (and its sidecar).

    Parameters
    ----------
    path : str or path-like
        The CSV file; ``NAME.json`` beside it is its sidecar.

    Returns
    -------
    Dataset

    Raises
    ------
    DataFileError
        Any problem, its message starting with ``file:line:column``.
    """
    path = str(path)
    raw_lines = _read_lines(path)
    meta, side = _load_sidecar(path)
    header, header_line, rows = split_csv(path, raw_lines)
    col_of = _columns(path, header, header_line)
    _check_polarization_columns(path, header_line, col_of)
    _check_incident_given_once(path, header_line, col_of, meta, side)
    if not rows:
        raise DataFileError(path, header_line, None, "no data rows")
    values, incident = _parse_rows(path, header, rows, col_of)
    if "incident_polarization" in meta:
        incident[:] = stokes(meta["incident_polarization"])
    eta, P, PC = _ellipsometric(values, len(rows))
    return Dataset(
        path=path,
        theta_i=np.radians(values["theta_i_deg"]),
        theta_r=np.radians(values["theta_r_deg"]),
        phi_r=np.radians(values["phi_r_deg"]),
        brdf=values["brdf"],
        incident=incident,
        brdf_err=values.get("brdf_err"),
        eta=eta,
        P=P,
        P_C=PC,
        eta_err=np.radians(values["eta_err_deg"]) if "eta_err_deg" in values else None,
        P_err=values.get("P_err"),
        P_C_err=values.get("P_C_err"),
        lines=np.array([ln for ln, _ in rows]),
        meta=meta,
    )


def write_data(path, columns: dict, meta: dict | None = None, comments=()):
    """Write a data file (and its sidecar when ``meta`` is given) atomically.

    ``columns`` maps column names (as in :data:`COLUMNS`, degrees) to arrays or,
    for ``incident``, to a list of strings.  Numbers are written with 17
    significant digits so a round trip is exact.
    """

    names = list(columns)
    for n in names:
        if n not in COLUMNS and n not in TEXT_COLUMNS:
            raise ValueError(f"columns: unknown column {n!r}")
    n_rows = {len(v) for v in columns.values()}
    if len(n_rows) != 1:
        raise ValueError("columns: every column must have the same length")
    buf = io.StringIO()
    for c in comments:  # one comment line each: a newline in a comment must not start a row
        buf.write("# " + " ".join(str(c).splitlines()) + "\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(names)
    cols = [columns[n] for n in names]
    for row in zip(*cols, strict=True):
        w.writerow([v if isinstance(v, str) else repr(float(v)) for v in row])
    atomic_write_text(path, buf.getvalue())
    if meta is not None:
        meta = {"format": FORMAT, **meta}
        atomic_write_json(_sidecar_path(path), meta)
