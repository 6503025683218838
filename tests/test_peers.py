"""benchmarks/peers.py: peers compared on the same quantity, absent peers skipped saying so,
the measured table written with its provenance.  Timings are faked here (one call each):
the benchmark measures, the tests check what it measures and records."""

import importlib.util
import json
import math
import os
import sys
import types

import numpy as np
import pytest

from scatterbench import models
from scatterbench.validation.checks.conformance_scatmech import scatmech_tolerance

#: how far Mitsuba may differ: float32 on its side (SCATMECH's limits are the registry's own,
#: validation.checks.conformance_scatmech.SCATMECH_TOL)
MITSUBA_AGREE = 1e-5
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.fixture(scope="module")
def peers():
    spec = importlib.util.spec_from_file_location("peers", os.path.join(ROOT, "benchmarks", "peers.py"))
    mod = importlib.util.module_from_spec(spec)
    sys.modules["peers"] = mod  # its dataclass looks its module up there
    try:
        spec.loader.exec_module(mod)
        yield mod
    finally:
        sys.modules.pop("peers", None)


@pytest.fixture
def one_call(peers, monkeypatch):
    """``time_call`` replaced by a single untimed-quality call (the tests check values, not speed)."""
    timing = types.SimpleNamespace(seconds=1e-6, wall_seconds=2e-6)
    monkeypatch.setattr(peers, "time_call", lambda fn: (fn(), timing))


def test_rel_diff_is_every_element_relative_to_m00(peers):
    theirs = np.zeros((2, 4, 4))
    theirs[:, 0, 0] = [2.0, 4.0]
    ours = theirs.copy()
    ours[0, 3, 1] += 0.02  # 0.01 of M00
    ours[1, 0, 0] += 0.02  # 0.005 of M00
    assert peers._rel_diff(ours, theirs) == pytest.approx(0.01)
    assert peers._rel_diff(np.array([1.0, 2.2]), np.array([1.0, 2.0])) == pytest.approx(0.1)


@pytest.mark.parametrize("missing, rows_of", [("pySCATMECH", "scatmech_rows"), ("mitsuba", "mitsuba_rows")])
def test_absent_peer_is_skipped_saying_so(peers, monkeypatch, missing, rows_of):
    for name in list(sys.modules):
        if name == missing or name.startswith(missing + "."):
            monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, missing, None)  # import raises ImportError
    rows, why = getattr(peers, rows_of)(peers.geometries(4), 2)
    assert rows == []
    text = why if isinstance(why, str) else " ".join(why)
    assert "not installed" in text and "pip install" in text


def test_mitsuba_scalar_matches_ours_on_the_same_geometries(peers):
    """Our geometry mapped to Mitsuba's directions gives the same BRDF (float32 on its side)."""
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    bsdf = mi.load_dict(
        {"type": "roughconductor", "distribution": "ggx", "alpha": 0.2, "eta": 1.37, "k": 7.62}
    )
    one = peers._scalar_one(mi, bsdf, polarized=False)
    ours = models.FacetBRDF(slopes=models.GGXSlopes(alpha=0.2), substrate=peers.AL, shadowing="smith")
    ti, tr, pr = peers.geometries(50, seed=7)
    theirs = np.array([one(a, b, c) for a, b, c in zip(ti, tr, pr, strict=True)])
    assert peers._rel_diff(ours.brdf(ti, tr, pr), theirs, floor=1e-20) < MITSUBA_AGREE
    # the comparison can fail: a geometry off by 0.3 rad in azimuth shows
    wrong = np.array([one(a, b, c + 0.3) for a, b, c in zip(ti, tr, pr, strict=True)])
    assert peers._rel_diff(ours.brdf(ti, tr, pr), wrong, floor=1e-20) > 1e-2


def test_main_writes_the_measured_table_with_provenance(peers, one_call, tmp_path, capsys, monkeypatch):
    if os.path.exists(peers.LLVM):  # main sets it when unset; restored after the test
        monkeypatch.setenv("DRJIT_LIBLLVM_PATH", peers.LLVM)
    out = tmp_path / "peer_timings.json"
    assert peers.main(["--n", "40", "--loop", "6", "--out", str(out)]) == 0
    table = json.loads(out.read_text())
    assert {"what", "date", "machine", "versions", "geometries", "rows", "skipped"} <= set(table)
    assert table["machine"]["cores"] == os.cpu_count() and len(table["machine"]["load_average_at_end"]) == 3
    assert table["versions"]["numpy"] == np.__version__ and table["geometries"] == {"array": 40, "loop": 6}
    peers_run = {r["peer"] for r in table["rows"]}
    for name, module in (("pySCATMECH", "pySCATMECH"), ("Mitsuba 3", "mitsuba")):
        if importlib.util.find_spec(module) is not None:
            assert name in peers_run
        else:
            assert name not in peers_run
            assert any(s.startswith(name.split()[0]) and "not installed" in s for s in table["skipped"])
    for r in table["rows"]:  # the same quantity on both sides: float32 on Mitsuba's, double on SCATMECH's
        agree = scatmech_tolerance(r["variant"]) if r["peer"] == "pySCATMECH" else MITSUBA_AGREE
        assert r["max_rel_diff"] < agree, r
        assert math.isclose(r["ours_call_us"], 1.0) and math.isclose(r["peer_call_wall_us"], 2.0)
    assert "ratio = peer / scatterbench" in capsys.readouterr().out


def test_our_timed_calls_run_on_one_thread(peers, monkeypatch):
    """The kernels' prange would use every core from 1024 geometries: pinned to one thread
    while timed (as Dr.Jit is), the count restored after, and recorded in the table."""
    numba = pytest.importorskip("numba")
    seen = []

    def record(fn):
        seen.append(numba.get_num_threads())
        return fn(), types.SimpleNamespace(seconds=1e-6, wall_seconds=2e-6)

    monkeypatch.setattr(peers, "time_call", record)
    before = numba.get_num_threads()
    m = models.FacetBRDF(slopes=models.ExponentialSlopes(0.1), substrate=peers.AL)
    peers.time_ours(m.mueller, peers.geometries(9000), 4)
    assert seen == [1, 1] and numba.get_num_threads() == before
    assert peers._machine()["threads"] == {
        "scatterbench (numba kernels)": 1,
        "Dr.Jit (Mitsuba LLVM variants)": 1,
    }


def test_bad_sizes_are_refused(peers):
    with pytest.raises(SystemExit):
        peers.main(["--n", "10", "--loop", "11", "--no-save"])


def test_a_jit_variant_that_fails_is_probed_in_a_child_process(peers):
    """A JIT variant Dr.Jit cannot run aborts its process inside LLVM (uncatchable): the
    probe runs it in a child, and a failure is a reason to skip, not a crash of this one."""
    pytest.importorskip("mitsuba")
    why = peers._jit_unusable("llvm_no_such_variant")
    assert why is not None and "probe process failed" in why and "libllvm19" in why
