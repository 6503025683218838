"""Published numbers and SCATMECH reference values, with provenance.

Data only: loaders return plain Python / numpy structures.  Every data file
starts with ``#`` comment lines saying where its numbers come from (the seed
and table, or the script and pySCATMECH version that generated them).
"""

from __future__ import annotations

import csv
import json
import math
import os
import tomllib

import numpy as np

__all__ = [
    "data_path",
    "read_csv",
    "provenance",
    "table1",
    "scatmech_facet",
    "table1_scatmech",
    "scene_paths",
    "scene_path",
    "seed003_presets",
    "iron_plate",
    "IRON_PLATE",
    "scatmech_seed003",
    "scatmech_flake_measurement_path",
]

_HERE = os.path.dirname(os.path.abspath(__file__))
_DATA = os.path.join(_HERE, "data")
_SCENES = os.path.join(_HERE, "scenes")


def data_path(name: str) -> str:
    return os.path.join(_DATA, name)


def provenance(name: str) -> str:
    """The leading ``#`` comment lines of a data file, without the ``#``."""
    lines = []
    with open(data_path(name), encoding="utf-8") as fh:
        for line in fh:
            if not line.startswith("#"):
                break
            lines.append(line[1:].strip())
    return "\n".join(lines)


def read_csv(name: str) -> list[dict]:
    """Rows of a committed CSV file (comment lines skipped) as dicts of strings."""
    with open(data_path(name), encoding="utf-8") as fh:
        rows = [line for line in fh if not line.startswith("#")]
    return list(csv.DictReader(rows))


def _index(text: str):
    return math.inf if text.strip() == "inf" else complex(text)


def table1() -> list[dict]:
    """Seed 000 Table I: 27 rows with substrate, index, coating, sigma, printed value."""
    out = []
    for r in read_csv("table1_seed000.csv"):
        out.append(
            {
                "substrate": r["substrate"],
                "index": _index(r["substrate_index"]),
                "coating": float(r["coating"]),
                "sigma": float(r["sigma"]),
                "printed": float(r["printed"]),
            }
        )
    return out


def scatmech_facet() -> dict:
    """SCATMECH Mueller BRDFs of the facet models: parameter columns and ``mueller`` (N, 4, 4)."""
    rows = read_csv("scatmech_facet.csv")
    out = {
        "model": np.array([r["model"] for r in rows]),
        "sdf": np.array([r["sdf"] for r in rows]),
    }
    for k in ("coating", "substrate_n", "substrate_k", "sigma", "theta_i", "theta_r", "phi_r"):
        out[k] = np.array([float(r[k]) for r in rows])
    out["mueller"] = np.array(
        [[float(r[f"m{i}{j}"]) for i in range(4) for j in range(4)] for r in rows]
    ).reshape(-1, 4, 4)
    return out


def table1_scatmech() -> dict:
    """SCATMECH-integrated Table I entries keyed by ``(substrate, coating, sigma)``."""
    out = {}
    for r in read_csv("table1_scatmech.csv"):
        key = (r["substrate"], float(r["coating"]), float(r["sigma"]))
        out[key] = {"value": float(r["reflectance"]), "grid_change": float(r["grid_change"])}
    return out


def scene_paths() -> list[str]:
    """Paths of the example scene files shipped with scatterbench (one per preset)."""
    return sorted(os.path.join(_SCENES, f) for f in os.listdir(_SCENES) if f.endswith(".toml"))


def scene_path(name: str) -> str:
    """Path of the shipped scene file ``name`` (e.g. ``"green_carc.toml"``)."""
    return os.path.join(_SCENES, name)


def _presets() -> dict:
    with open(data_path("presets.toml"), "rb") as fh:
        return tomllib.load(fh)


def seed003_presets() -> dict:
    """Seed 003's paper presets (Fig. 2-3), by name in sorted order: ``scene`` (the path of
    the scene file that holds the model and its numbers; load it with
    ``models.scene.load``), ``sample``, ``figure``, ``model`` (a label), ``printed``
    (False: the numbers are our placeholders) and ``source`` (the quote)."""
    out = {}
    for name, p in sorted(_presets()["seed003"].items()):
        out[name] = {**p, "scene": scene_path(p["scene"])}
    return out


def iron_plate() -> dict:
    """Seed 001's iron plate ("Measurement Results"): ``m``, ``varnish`` (n_v),
    ``substrate`` (complex iron index), ``wavelength_nm``, ``incidence_ranges_deg``
    (the printed ranges of incidence over the sample, ``(lo, hi)`` pairs) and ``source``."""
    p = _presets()["seed001"]["iron_plate"]
    return {
        "m": p["m"],
        "varnish": p["varnish"],
        "substrate": complex(*p["substrate"]),
        "wavelength_nm": p["wavelength_nm"],
        "incidence_ranges_deg": tuple(tuple(r) for r in p["incidence_ranges_deg"]),
        "source": p["source"],
    }


#: Seed 001's iron plate (:func:`iron_plate`).
IRON_PLATE = iron_plate()


def scatmech_seed003(kind: str) -> dict:
    """SCATMECH Mueller BSDFs for the seed 003 models; ``kind`` is ``diffuse``,
    ``single``, ``btdf`` or ``mb`` (Maxwell-Beard specular term).  Parameter columns (floats; ``sdf`` a string) and
    ``mueller`` ``(N, 4, 4)``."""
    if kind not in ("diffuse", "single", "btdf", "mb"):
        raise ValueError(f"kind must be 'diffuse', 'single', 'btdf' or 'mb'; got {kind!r}")
    rows = read_csv(f"scatmech_seed003_{kind}.csv")
    out = {}
    for k in rows[0]:
        if k.startswith("m") and len(k) == 3 and k[1:].isdigit():
            continue
        out[k] = np.array([r[k] for r in rows]) if k == "sdf" else np.array([float(r[k]) for r in rows])
    out["mueller"] = np.array(
        [[float(r[f"m{i}{j}"]) for i in range(4) for j in range(4)] for r in rows]
    ).reshape(-1, 4, 4)
    return out


def scatmech_flake_measurement_path() -> str:
    """Path of the held-out synthetic measurement of a coated aluminium-flake sample,
    generated by SCATMECH (``references/scripts/make_scatmech_flake_data.py``; truth,
    seed, noise model and pySCATMECH version in its JSON sidecar).  Read it with
    ``validation.fitting.datafile.load_data``."""
    return data_path("scatmech_flake_measurement.csv")


# Peer references (Mitsuba 3, tmm): committed evaluations the tests read; the peers are never imported here
__all__ += ["mitsuba_roughconductor", "tmm_reference", "tmm_both_ways", "peer_timings"]


def peer_timings() -> dict:
    """scatterbench's and its peers' (pySCATMECH, Mitsuba 3) timings, measured in one run by
    ``benchmarks/peers.py`` (``references/data/peer_timings.json``): ``what``, ``date``,
    ``machine`` (``cpu``, ``cores``, ``platform``, ``load_average_at_start`` and ``_at_end``,
    ``threads`` per side), ``versions``, ``geometries`` and ``rows``, one dict per pair with
    ``model``, ``peer``, ``variant``, per-call and per-geometry microseconds on each side
    (``ours_call_us``, ``peer_call_us``, ``ours_geometry_us``, ``peer_geometry_us``: CPU time;
    ``*_wall_us``: wall clock) and ``max_rel_diff``; ``skipped``: peers not measured, why."""
    with open(data_path("peer_timings.json"), encoding="utf-8") as fh:
        return json.load(fh)


def mitsuba_roughconductor() -> dict:
    """Mitsuba 3 ``roughconductor`` evaluations (``references/scripts/make_mitsuba_roughconductor.py``):
    string columns ``variant``, ``distribution``; float columns ``alpha, eta, k, theta_i,
    theta_r, phi_r, value``; for the polarized rows ``mueller`` ``(N, 4, 4)`` in Mitsuba's
    frames and ``x_in``, ``x_out`` ``(N, 3)`` (NaN in the unpolarized rows)."""
    rows = read_csv("mitsuba_roughconductor.csv")
    out = {k: np.array([r[k] for r in rows]) for k in ("variant", "distribution")}

    def col(k):
        return np.array([float(r[k]) if r[k] else math.nan for r in rows])

    for k in ("alpha", "eta", "k", "theta_i", "theta_r", "phi_r", "value"):
        out[k] = col(k)
    out["mueller"] = np.stack([col(f"m{i}{j}") for i in range(4) for j in range(4)], -1).reshape(-1, 4, 4)
    out["x_in"] = np.stack([col(f"xin_{c}") for c in "xyz"], -1)
    out["x_out"] = np.stack([col(f"xout_{c}") for c in "xyz"], -1)
    return out


def _tmm_case(r):
    films = []
    for part in r["layers"].split("|"):
        n, k, d = (float(x) for x in part.split(";"))
        films.append((complex(n, k), d))
    case = {"n0": float(r["n0"]), "films": films, "wavelength_nm": float(r["wavelength_nm"])}
    case["substrate"] = complex(float(r["substrate_n"]), float(r["substrate_k"]))
    case["theta0"] = float(r["theta0"])
    for c in ("rs", "rp", "ts", "tp"):
        case[c] = complex(float(r[f"{c}_re"]), float(r[f"{c}_im"]))
    return case


def tmm_reference() -> list[dict]:
    """``tmm`` thin-film coefficients (``references/scripts/make_tmm_reference.py``, its
    "random" rows): one dict per case with ``n0``, ``films`` (list of ``(index,
    thickness_nm)``), ``substrate``, ``wavelength_nm``, ``theta0`` and complex ``rs, rp, ts, tp``."""
    return [_tmm_case(r) for r in read_csv("tmm_reference.csv") if r["role"] == "random"]


def tmm_both_ways() -> list[tuple[dict, dict]]:
    """``tmm``'s films on a coating crossed both ways (the same file's "down" and "up" rows):
    ``(down, up)`` pairs of :func:`tmm_reference`'s dicts, each with tmm's power
    transmittances ``T_s``, ``T_p`` besides.  ``down``: from the ambient (``n0 = 1``) onto the
    coating (``substrate``); ``up``: from the coating through the films reversed into the
    ambient, at the refracted angle."""
    rows = [r for r in read_csv("tmm_reference.csv") if r["role"] != "random"]
    cases = []
    for r in rows:
        case = _tmm_case(r)
        case["T_s"], case["T_p"] = float(r["T_s"]), float(r["T_p"])
        cases.append(case)
    if [r["role"] for r in rows] != ["down", "up"] * (len(rows) // 2):
        raise ValueError("tmm_reference.csv: each 'down' row must be followed by its 'up' row")
    return list(zip(cases[::2], cases[1::2], strict=True))


# NIST's sintered PTFE (T. A. Germer, Applied Optics 2017; a U.S. government work): the files are
# committed as published in data/nist_ptfe/, with PROVENANCE.md beside them
__all__ += ["nist_ptfe_path", "nist_ptfe_coefficients", "NIST_PTFE_TABLES", "read_coefficient_table"]

_NIST = os.path.join(_DATA, "nist_ptfe")

#: name -> file of the published expansion-coefficient tables (data/nist_ptfe/)
NIST_PTFE_TABLES = {
    "351": "PTFE.351.coeff.csv",
    "532": "PTFE.532.coeff.csv",
    "633": "PTFE.633.coeff.csv",
    "1064": "PTFE.1064.coeff.csv",
    "all": "PTFE.coeff.csv",
    "grey10.532": "PTFE.grey10.532.coef.csv",
}


def nist_ptfe_path(name: str = "PTFE.data.csv") -> str:
    """Path of a file of NIST's sintered-PTFE supplementary data (``data/nist_ptfe/``, as
    published; provenance in ``PROVENANCE.md`` there): by default the 7296 measurements,
    read with :func:`scatterbench.validation.fitting.mueller_data.load_mueller_data`."""
    return os.path.join(_NIST, name)


def read_coefficient_table(path) -> tuple:
    """The rows of a SCATMECH ``ZernikeExpansion_BRDF_Model`` coefficient file, ``(i, j, n, m,
    k, l, p, a)`` each (seven ints and a float), in file order.  Fields are separated by commas
    and/or blanks; blank lines are skipped.  A line that is not eight numbers, or an index that
    is not an integer, is a ``ValueError`` naming ``file:line``."""
    rows = []
    with open(path, encoding="utf-8") as fh:
        for lineno, text in enumerate(fh, 1):
            fields = text.replace(",", " ").split()
            if not fields:
                continue
            try:
                values = [float(f) for f in fields]
            except ValueError:
                raise ValueError(f"{path}:{lineno}: not a coefficient line (eight numbers)") from None
            if len(values) != 8 or any(v != int(v) for v in values[:7] if math.isfinite(v)):
                raise ValueError(
                    f"{path}:{lineno}: expected i, j, n, m, k, l, p (integers) and a; got {text.strip()!r}"
                )
            rows.append((*(int(v) for v in values[:7]), values[7]))
    return tuple(rows)


def nist_ptfe_coefficients(name: str) -> tuple:
    """A published expansion-coefficient table of NIST's sintered PTFE by name: ``"351"``,
    ``"532"``, ``"633"``, ``"1064"`` (fitted to that wavelength's measurements), ``"all"``
    (all four, with ``lambda^p`` terms, lambda in micrometres) or ``"grey10.532"`` (a grey
    PTFE).  Rows ``(i, j, n, m, k, l, p, a)``, the ``coefficients`` of
    :class:`scatterbench.models.ZernikeExpansionBRDF`."""
    if name not in NIST_PTFE_TABLES:
        raise ValueError(f"name must be one of {', '.join(map(repr, NIST_PTFE_TABLES))}; got {name!r}")
    return read_coefficient_table(nist_ptfe_path(NIST_PTFE_TABLES[name]))
