"""Data files: format, round trip, and malformed input rejected with file:line:column."""

import json
import os

import numpy as np
import pytest

from scatterbench import references
from scatterbench.validation.fitting.datafile import DataFileError, load_data, write_data

SCATMECH = references.data_path("scatmech_flake_measurement.csv")
HEAD = "theta_i_deg,theta_r_deg,phi_r_deg,brdf,incident\n"


def _write(tmp_path, text, name="d.csv", sidecar=None):
    p = tmp_path / name
    p.write_text(text)
    if sidecar is not None:
        (tmp_path / (os.path.splitext(name)[0] + ".json")).write_text(sidecar)
    return str(p)


def test_scatmech_data_set_loads_with_truth_and_provenance():
    d = load_data(SCATMECH)
    assert len(d) == 200
    assert d.meta["truth"]["substrate.sigma"] == 0.1
    assert d.meta["provenance"]["pyscatmech_version"]
    assert d.eta is not None and d.P is not None and d.P_C is not None
    assert np.all(d.brdf > 0) and d.incident.shape == (200, 4)
    # out-of-plane rows turn the incident polarization with phi (45 + phi/2 deg)
    row = np.flatnonzero(np.isclose(np.degrees(d.phi_r), 90.0, atol=3.1) & np.isclose(d.theta_r, d.theta_i))[
        0
    ]
    a = np.radians(45 + np.degrees(d.phi_r[row]) / 2)
    assert np.allclose(d.incident[row], [1, np.cos(2 * a), np.sin(2 * a), 0], atol=1e-12)


def test_round_trip_is_exact(tmp_path):
    rng = np.random.default_rng(1)
    cols = {
        "theta_i_deg": rng.uniform(0, 89, 7),
        "theta_r_deg": rng.uniform(0, 89, 7),
        "phi_r_deg": rng.uniform(-180, 180, 7),
        "brdf": rng.uniform(1e-6, 10, 7),
        "brdf_err": rng.uniform(1e-7, 1, 7),
        "s1": rng.uniform(-1, 1, 7),
        "s2": rng.uniform(-1, 1, 7),
        "s3": rng.uniform(-0.1, 0.1, 7),
    }
    p = str(tmp_path / "r.csv")
    write_data(p, cols, {"incident_polarization": "p", "wavelength_nm": 632.8, "sample": "x"}, ["made here"])
    d = load_data(p)
    assert np.array_equal(np.degrees(d.theta_r), np.degrees(np.radians(cols["theta_r_deg"])))
    assert np.array_equal(d.brdf, cols["brdf"]) and np.array_equal(d.brdf_err, cols["brdf_err"])
    assert np.allclose(d.eta, 0.5 * np.arctan2(cols["s2"], cols["s1"]))
    assert np.allclose(d.incident, [1, -1, 0, 0])
    assert d.meta["sample"] == "x"


@pytest.mark.parametrize(
    "body, where, words",
    [
        ("60,10,0,abc,s\n", ":3:4:", ["brdf", "not a number", "'abc'"]),
        ("60,95,0,1.0,s\n", ":3:2:", ["theta_r_deg", "outside [0, 90)"]),
        ("60,10,0,nan,s\n", ":3:4:", ["brdf", "not a finite number"]),
        ("60,10,0,,s\n", ":3:4:", ["brdf", "missing value"]),
        ("60,10,0,-1,s\n", ":3:4:", ["brdf", "outside (0, inf)"]),
        ("60,10,0,1\n", ":3:5:", ["expected 5 fields"]),
        ("60,10,0,1,sideways\n", ":3:5:", ["incident", "polarization must be one of"]),
    ],
)
def test_malformed_rows_name_file_line_column(tmp_path, body, where, words):
    p = _write(tmp_path, "# comment\n" + HEAD + body)
    with pytest.raises(DataFileError) as e:
        load_data(p)
    msg = str(e.value)
    assert msg.startswith(p + where), msg
    for w in words:
        assert w in msg


def test_missing_column_and_radian_names(tmp_path):
    p = _write(tmp_path, "theta_i_deg,theta_r_deg,brdf,incident\n60,10,1,s\n")
    with pytest.raises(DataFileError, match=r"d\.csv:1: missing required column 'phi_r_deg'"):
        load_data(p)
    p = _write(tmp_path, "theta_i,theta_r_deg,phi_r_deg,brdf,incident\n1,0.2,0,1,s\n")
    with pytest.raises(DataFileError, match=r"d\.csv:1:1: unknown column 'theta_i' \(angles are in degrees"):
        load_data(p)


def test_incident_polarization_must_be_given_exactly_once(tmp_path):
    p = _write(tmp_path, "theta_i_deg,theta_r_deg,phi_r_deg,brdf\n60,10,0,1\n")
    with pytest.raises(DataFileError, match="missing column 'incident'"):
        load_data(p)
    p = _write(tmp_path, HEAD + "60,10,0,1,s\n", sidecar=json.dumps({"incident_polarization": "p"}))
    with pytest.raises(DataFileError, match="given twice"):
        load_data(p)


def test_polarization_columns_are_complete_and_not_doubled(tmp_path):
    p = _write(tmp_path, "theta_i_deg,theta_r_deg,phi_r_deg,brdf,s1,s2,incident\n60,10,0,1,0.1,0.2,s\n")
    with pytest.raises(DataFileError, match="s3"):
        load_data(p)
    p = _write(tmp_path, "theta_i_deg,theta_r_deg,phi_r_deg,brdf,s1,s2,s3,P,incident\n60,10,0,1,0,0,0,1,s\n")
    with pytest.raises(DataFileError, match="not both"):
        load_data(p)


def test_sidecar_errors_name_line_and_key(tmp_path):
    p = _write(
        tmp_path, HEAD + "60,10,0,1,s\n", sidecar='{\n  "wavelength_nm": 632.8,\n  "colour": "red"\n}\n'
    )
    with pytest.raises(DataFileError, match=r"d\.json:3:3: unknown key 'colour'"):
        load_data(p)
    p = _write(tmp_path, HEAD + "60,10,0,1,s\n", sidecar='{\n  "wavelength_nm": -5\n}\n')
    with pytest.raises(DataFileError, match=r"d\.json:2:3: wavelength_nm must be a finite number > 0"):
        load_data(p)
    p = _write(tmp_path, HEAD + "60,10,0,1,s\n", sidecar='{\n  "sample": "a",,\n}\n')
    with pytest.raises(DataFileError, match=r"d\.json:2:\d+: not valid JSON"):
        load_data(p)
