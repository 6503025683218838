"""The Mueller-BRDF data format, NIST's published file and the explicit conversions
(validation/fitting/mueller_data.py)."""

import math

import numpy as np
import pytest

from scatterbench import references
from scatterbench.models.geometry import sp_basis
from scatterbench.models.polarization import basis_rotation, jones_to_mueller, psps_to_xyxy, xyxy_to_psps
from scatterbench.validation.fitting.datafile import DataFileError
from scatterbench.validation.fitting.mueller_data import (
    ELEMENTS,
    absolute_to_normalized,
    fold_negative_polar,
    load_mueller_data,
    normalized_to_absolute,
    relative_azimuth,
    to_basis,
)

GEOMETRY = "theta_i_deg,phi_i_deg,theta_r_deg,phi_r_deg"
NORMALIZED = ",".join(f"{e}/m11" for e in ELEMENTS[1:])
ABSOLUTE = ",".join(ELEMENTS[1:])


def _write(tmp_path, text, name="m.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return str(path)


def _row(values15, geometry="30,180,40,20", wl="532", m11="0.3"):
    return f"{geometry},{wl},{m11}," + ",".join(str(v) for v in values15)


def _normalized_file(tmp_path, rows, basis="psps", wl_col="wavelength_nm"):
    head = f"# basis: {basis}\n{GEOMETRY},{wl_col},m11,{NORMALIZED}\n"
    return _write(tmp_path, head + "\n".join(rows) + "\n")


def _error(path):
    with pytest.raises(DataFileError) as exc:
        load_mueller_data(path)
    return str(exc.value)


# ------------------------------------------------------------------ reading the format
def test_normalized_and_absolute_forms_read_the_same_matrix(tmp_path):
    N = np.linspace(-0.2, 0.5, 15)
    a = load_mueller_data(_normalized_file(tmp_path, [_row(N)]))
    head = f"# basis: psps\n{GEOMETRY},wavelength_um,m11,{ABSOLUTE},m11_err\n"
    b = load_mueller_data(_write(tmp_path, head + _row(0.3 * N, wl="0.532") + ",0.01\n", "b.csv"))
    assert a.basis == b.basis == "psps" and len(a) == 1
    # the file holds 0.3 N written out: equal to rounding (linspace's zero is -1.4e-17)
    np.testing.assert_allclose(a.mueller, b.mueller, rtol=1e-15, atol=1e-16)
    np.testing.assert_allclose(a.mueller[0].ravel()[1:], 0.3 * N)
    assert a.wavelength_nm[0] == b.wavelength_nm[0] == 532.0
    assert b.err[0, 0, 0] == 0.01 and np.isnan(b.err[0, 0, 1]) and not b.err_normalized
    assert a.theta_i[0] == pytest.approx(math.radians(30)) and a.phi_i[0] == pytest.approx(math.pi)


def test_normalized_absolute_round_trip():
    rng = np.random.default_rng(3)
    M = rng.normal(size=(5, 4, 4))
    M[:, 0, 0] = rng.uniform(0.1, 2.0, 5)
    m11, N = absolute_to_normalized(M)
    np.testing.assert_allclose(normalized_to_absolute(m11, N), M, rtol=1e-15)
    assert np.all(N[:, 0, 0] == 1.0)


# ------------------------------------------------------------------ the loader's errors
def test_wavelength_in_the_wrong_unit_is_named_both_ways(tmp_path):
    msg = _error(_normalized_file(tmp_path, [_row(np.zeros(15), wl="0.532")]))
    assert ":3:" in msg and "'wavelength_nm'" in msg and "looks like um" in msg and "wavelength_um" in msg
    msg = _error(_normalized_file(tmp_path, [_row(np.zeros(15), wl="633")], wl_col="wavelength_um"))
    assert "'wavelength_um'" in msg and "looks like nm" in msg and "[0.1, 20] um" in msg
    msg = _error(_normalized_file(tmp_path, [_row(np.zeros(15), wl="1e6")]))
    assert "outside [100, 20000] nm" in msg and "looks like" not in msg


def test_normalized_element_beyond_1_5_names_line_column_and_range(tmp_path):
    N = np.zeros(15)
    N[4] = 1.6  # m22/m11 is the 5th normalized element: column 6 + 5 = 11
    path = _normalized_file(tmp_path, [_row(np.zeros(15)), _row(N, geometry="30,180,40,25")])
    msg = _error(path)
    assert msg.startswith(f"{path}:4:11:") and "'m22/m11'" in msg and "[-1.5, 1.5]" in msg


def test_absolute_element_beyond_1_5_m11(tmp_path):
    head = f"# basis: psps\n{GEOMETRY},wavelength_nm,m11,{ABSOLUTE}\n"
    values = np.zeros(15)
    values[2] = -0.5  # |m14| = 0.5 > 1.5 * 0.3
    msg = _error(_write(tmp_path, head + _row(values) + "\n"))
    assert ":3:9:" in msg and "'m14'" in msg and "1.5 m11" in msg


@pytest.mark.parametrize("m11", ["0", "-0.2"])
def test_m11_not_positive(tmp_path, m11):
    msg = _error(_normalized_file(tmp_path, [_row(np.zeros(15), m11=m11)]))
    assert ":3:6:" in msg and "'m11'" in msg and "not > 0" in msg


def test_incomplete_set_of_elements(tmp_path):
    cols = ",".join(f"{e}/m11" for e in ELEMENTS[1:-1])  # m44/m11 missing
    msg = _error(
        _write(tmp_path, f"# basis: psps\n{GEOMETRY},wavelength_nm,m11,{cols}\n" + _row(np.zeros(14)) + "\n")
    )
    assert ":2:" in msg and "incomplete Mueller matrix" in msg and "m44/m11" in msg
    mixed = NORMALIZED.replace("m12/m11", "m12")
    msg = _error(
        _write(tmp_path, f"# basis: psps\n{GEOMETRY},wavelength_nm,m11,{mixed}\n" + _row(np.zeros(15)) + "\n")
    )
    assert "not both" in msg


def test_duplicated_geometry_with_conflicting_values(tmp_path):
    N = np.zeros(15)
    M = N.copy()
    M[0] = 0.1
    same = _normalized_file(tmp_path, [_row(N), _row(N, geometry="30,-180,40,-340")])
    assert len(load_mueller_data(same)) == 2  # an identical repeat (azimuths modulo 360) is no conflict
    path = _normalized_file(
        tmp_path, [_row(N), _row(N, geometry="30,0,40,0"), _row(M, geometry="30,-180,40,-340")]
    )
    msg = _error(path)
    assert msg.startswith(f"{path}:5:") and "line 3" in msg and "different elements" in msg


def test_basis_must_be_stated_and_known(tmp_path):
    text = f"{GEOMETRY},wavelength_nm,m11,{NORMALIZED}\n" + _row(np.zeros(15)) + "\n"
    assert "missing '# basis: psps'" in _error(_write(tmp_path, text))
    msg = _error(_write(tmp_path, "# basis: sp\n" + text, "c.csv"))
    assert ":1:10:" in msg and "psps, xyxy" in msg


def test_negative_polar_angle_points_to_the_conversion(tmp_path):
    msg = _error(_normalized_file(tmp_path, [_row(np.zeros(15), geometry="-30,0,40,20")]))
    assert ":3:1:" in msg and "'theta_i_deg'" in msg and "fold_negative_polar" in msg


def test_not_a_number_and_field_count(tmp_path):
    assert ":3:3:" in _error(_normalized_file(tmp_path, [_row(np.zeros(15), geometry="30,180,x,20")]))
    assert "expected 21 fields" in _error(_normalized_file(tmp_path, [_row(np.zeros(14))]))


# ------------------------------------------------------------------ the conversions
def test_fold_negative_polar_is_the_signed_direction():
    theta = np.radians([-45.0, 45.0, -0.001, -75.0])
    phi = np.radians([0.0, 0.0, 0.0, 30.0])
    t, p = fold_negative_polar(theta, phi)
    signed = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1)
    folded = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1)
    np.testing.assert_allclose(folded, signed, atol=1e-15)
    assert np.all(t >= 0) and p[0] == pytest.approx(math.pi)


def test_relative_azimuth_standard_geometry():
    # the source at azimuth pi is the standard geometry: phi_r unchanged; turning both keeps it
    assert relative_azimuth(math.pi, 0.3) == pytest.approx(0.3)
    assert relative_azimuth(math.pi + 1.0, 1.3) == pytest.approx(0.3)
    assert relative_azimuth(0.0, 0.0) == pytest.approx(math.pi)  # retroreflection


def _scatmech_xy(k):
    """SCATMECH's GetBasisVectorsXY (code/jmatrix.cpp), from its definition: s = unit(z x k),
    p = k x s; x = -p kx - s ky (upward k) or p kx - s ky (downward), (kx, ky) the unit
    horizontal direction; y = unit(x x k); the Jones vector is ordered (y, x) like (s, p)."""
    s = np.cross([0.0, 0.0, 1.0], k)
    s /= np.linalg.norm(s)
    p = np.cross(k, s)
    kx, ky = k[:2] / np.hypot(k[0], k[1])
    x = (-p * kx - s * ky) if k[2] > 0 else (p * kx - s * ky)
    y = np.cross(x, k)
    return y / np.linalg.norm(y), x


def _mueller(J):
    return jones_to_mueller(np.array([J], dtype=complex))[0]


def test_xyxy_to_psps_is_scatmechs_basis_change():
    """The closed form R(-phi_r) M R(-phi_i) against SCATMECH's vector construction, for random
    general geometries: the Jones rotators J_ab = e_a(psps) . e_b(xyxy) on each ray, as Mueller
    matrices (BRDF_Model::convert)."""
    rng = np.random.default_rng(7)
    for _ in range(20):
        ti, tr = rng.uniform(0.05, 1.5, 2)
        phi_i, phi_r = rng.uniform(-math.pi, math.pi, 2)
        k_in = -np.array([np.sin(ti) * np.cos(phi_i), np.sin(ti) * np.sin(phi_i), np.cos(ti)])
        k_out = np.array([np.sin(tr) * np.cos(phi_r), np.sin(tr) * np.sin(phi_r), np.cos(tr)])
        s_in, p_in = sp_basis(k_in)
        s_out, p_out = sp_basis(k_out)
        y_in, x_in = _scatmech_xy(k_in)
        y_out, x_out = _scatmech_xy(k_out)
        rot_out = _mueller([[s_out @ y_out, s_out @ x_out], [p_out @ y_out, p_out @ x_out]])
        rot_in = _mueller([[y_in @ s_in, y_in @ p_in], [x_in @ s_in, x_in @ p_in]])
        M_xy = rng.normal(size=(4, 4))
        np.testing.assert_allclose(xyxy_to_psps(M_xy, phi_i, phi_r), rot_out @ M_xy @ rot_in, atol=1e-12)
        np.testing.assert_allclose(
            psps_to_xyxy(xyxy_to_psps(M_xy, phi_i, phi_r), phi_i, phi_r), M_xy, atol=1e-12
        )


def test_basis_rotation_signs():
    # e1 = cos(a) s + sin(a) p at a = 45 deg: light polarized along e1 is +45 in (s, p), U = +1
    np.testing.assert_allclose(basis_rotation(math.pi / 4) @ [1, 1, 0, 0], [1, 0, 1, 0], atol=1e-15)
    # the standard geometry: the incident factor is the identity, in-plane the bases agree
    M = np.arange(16.0).reshape(4, 4)
    np.testing.assert_allclose(to_basis(M, math.pi, math.pi, "xyxy", "psps"), M, atol=1e-12)
    np.testing.assert_allclose(
        to_basis(M, math.pi, 0.7, "xyxy", "psps"), basis_rotation(-0.7) @ M, atol=1e-12
    )


# ------------------------------------------------------------------ NIST's file as published
@pytest.fixture(scope="module")
def nist():
    return load_mueller_data(references.nist_ptfe_path())


def test_nist_file_is_read_as_published(nist):
    assert len(nist) == 7296 and nist.basis == "xyxy"
    assert sorted(set(nist.wavelength_nm)) == [351.0, 532.0, 633.0, 1064.0]
    # every incidence is written as a negative polar angle at phi = 0: light from azimuth 180
    np.testing.assert_allclose(nist.phi_i, math.pi)
    assert np.all(nist.theta_i >= 0) and np.all(nist.theta_r >= 0)
    raw = np.genfromtxt(references.nist_ptfe_path(), delimiter=",", skip_header=1, max_rows=3)
    np.testing.assert_allclose(nist.mueller[:3, 0, 0], raw[:, 5])
    np.testing.assert_allclose(nist.normalized()[:3].reshape(3, 16)[:, 1:], raw[:, 6:])
    ti, tr, pr = nist.relative_geometry()
    np.testing.assert_allclose(np.degrees(pr[0]), -156.038, atol=1e-9)  # phi_i = 180: phi_r as given


def test_nist_reader_errors_name_nist_columns(tmp_path):
    lines = open(references.nist_ptfe_path(), encoding="utf-8").read().splitlines()[:3]
    bad = lines[2].split(",")
    bad[0] = "532"  # nanometres in NIST's micrometre column
    msg = _error(_write(tmp_path, "\n".join([lines[0], lines[1], ",".join(bad)]) + "\n"))
    assert ":3:" in msg and "looks like nm" in msg
    bad = lines[2].split(",")
    bad[9] = "2.5"
    msg = _error(_write(tmp_path, "\n".join([lines[0], ",".join(bad)]) + "\n", "n.csv"))
    assert ":2:10:" in msg and "'f_r21/f_r11'" in msg and "[-1.5, 1.5]" in msg


# ------------------------------------------------------------------ the bad-input list
def test_wavelength_unit_errors_give_line_and_column(tmp_path):
    msg = _error(_normalized_file(tmp_path, [_row(np.zeros(15), wl="0.532")]))
    assert ":3:5:" in msg  # wavelength_nm is the fifth column
    lines = open(references.nist_ptfe_path(), encoding="utf-8").read().splitlines()[:3]
    bad = lines[2].split(",")
    bad[0] = "532"
    msg = _error(_write(tmp_path, "\n".join([lines[0], lines[1], ",".join(bad)]) + "\n", "n.csv"))
    assert ":3:1:" in msg and "column 'lambda'" in msg and "[0.1, 20] um" in msg


def test_nist_m11_not_positive_and_conflicting_duplicate(tmp_path):
    lines = open(references.nist_ptfe_path(), encoding="utf-8").read().splitlines()[:3]
    bad = lines[2].split(",")
    bad[5] = "0"
    msg = _error(_write(tmp_path, "\n".join([lines[0], lines[1], ",".join(bad)]) + "\n"))
    assert ":3:6:" in msg and "'f_r11'" in msg and "not > 0" in msg
    dup = lines[1].split(",")
    dup[6] = str(float(dup[6]) + 0.01)
    msg = _error(_write(tmp_path, "\n".join([lines[0], lines[1], ",".join(dup)]) + "\n", "d.csv"))
    assert ":3:" in msg and "line 2" in msg and "different elements" in msg


def test_nist_header_with_a_column_missing_is_named(tmp_path):
    lines = open(references.nist_ptfe_path(), encoding="utf-8").read().splitlines()[:2]
    head, row = lines[0].split(","), lines[1].split(",")
    text = ",".join(head[:-1]) + "\n" + ",".join(row[:-1]) + "\n"
    msg = _error(_write(tmp_path, text))
    assert ":1:" in msg and "missing f_r44/f_r11" in msg and "21 columns" in msg
