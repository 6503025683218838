"""The HTML report and the nightly run: numbers equal results.json, escaping, regressions, kills."""

import html
import json
import os
import re

import pytest

import models.facet
from validation.report import build_report, nightly


def _cells(page, key):
    m = re.search(rf'<table data-key="{re.escape(key)}">(.*?)</table>', page, re.S)
    assert m, key
    return [html.unescape(c) for c in re.findall(r"<td[^>]*>(.*?)</td>", m.group(1), re.S)]


@pytest.fixture(scope="module")
def table1_report():
    return build_report(quick=True, only=["table1"], checks=["seed000.check_table1"])


def test_sections_present_and_numbers_match_results(table1_report):
    results, page = table1_report
    for sid in ("summary", "table1", "provenance"):
        assert f'id="{sid}"' in page and sid in results["sections"]
    rows = results["sections"]["table1"]["numbers"]["table1"]
    assert len(rows) == 27
    cells = _cells(page, "table1")
    ncol = len(rows[0])
    for i, r in enumerate(rows):
        shown = cells[i * ncol : (i + 1) * ncol]
        assert shown[4] == format(r["scatterbench"], ".4f")
        assert shown[3] == format(r["paper"], ".2f")
        assert shown[6] == format(r["independent"], ".4f")
    assert results["summary"]["n_fail"] == 0
    json.dumps(results)  # serializable as written


def test_page_is_self_contained(table1_report):
    _, page = table1_report
    assert "http://" not in page and "https://" not in page
    assert "<script" not in page


def test_scene_names_are_escaped(tmp_path):
    evil = tmp_path / "evil.toml"
    evil.write_text(
        'name = "<script>alert(1)</script> flakes"\n[illumination]\ntheta_i_deg = 45\n'
        '[substrate]\nindex = 1.5\ndistribution = "gaussian"\nsigma = 0.2\n'
    )
    _, page = build_report(quick=True, only=["scenes"], checks=[], extra_scenes=[str(evil)])
    assert "&lt;script&gt;alert(1)&lt;/script&gt; flakes" in page
    assert "<script>alert(1)" not in page
    # every scene states how its source and detector are evaluated, and why (measured)
    assert "detector aperture 0.7 deg kept" in page and "point source at d/R = 10 kept" in page


def test_nightly_history_regression_and_kill(tmp_path, monkeypatch):
    hist = str(tmp_path / "hist")
    kw = dict(quick=True, only=["table1"], checks=["seed000.check_table1"])
    code, reg, run1, _ = nightly(hist, stamp="2026-01-01T000000Z", **kw)
    assert code == 0 and reg == []
    assert os.path.realpath(os.path.join(hist, "latest")) == os.path.realpath(run1)

    # Break the model: flip the sign of the facet's s reflection coefficient.
    real = models.facet.reflection_rs_k

    def broken(c, m):
        rs, k = real(c, m)
        return -rs, k

    monkeypatch.setattr(models.facet, "reflection_rs_k", broken)
    with models.backend("numpy"):  # the patched function is the numpy path's (kernels: models.kernels)
        code, reg, run2, _ = nightly(hist, stamp="2026-01-02T000000Z", **kw)
    assert code != 0 and reg
    assert any("passed before and now fails" in r for r in reg)
    assert any("moved from" in r for r in reg)
    with open(os.path.join(run2, "results.json")) as fh:
        res2 = json.load(fh)
    red = [c["name"] for c in res2["checks"] if c["status"] == "fail"]
    assert any("SCATMECH" in n for n in red)
    monkeypatch.setattr(models.facet, "reflection_rs_k", real)

    # A run killed before its commit point leaves latest and the history untouched.
    before = sorted(os.listdir(os.path.join(hist, "runs")))

    def kill(_tmp):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        nightly(hist, stamp="2026-01-03T000000Z", _after_build=kill, **kw)
    assert sorted(os.listdir(os.path.join(hist, "runs"))) == before
    assert os.path.realpath(os.path.join(hist, "latest")) == os.path.realpath(run2)
    with open(os.path.join(hist, "latest", "results.json")) as fh:
        assert json.load(fh) == res2
    # the next run cleans the leftover and compares with the last completed night (the broken one)
    code, reg, run4, _ = nightly(hist, stamp="2026-01-04T000000Z", **kw)
    assert not [n for n in os.listdir(hist) if n.startswith(".tmp-")]
    # the repaired figures moved back: a moved figure is flagged whatever its direction,
    # but no check went from pass to fail
    assert reg and not any("passed before and now fails" in r for r in reg)
    code, reg, _, _ = nightly(hist, stamp="2026-01-05T000000Z", **kw)
    assert code == 0 and reg == []
