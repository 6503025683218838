"""The HTML report and the nightly run: numbers equal results.json, escaping, regressions, kills."""

import ast
import dataclasses
import html
import json
import os
import pathlib
import re
import sys

import markupsafe
import pytest

import scatterbench.models.facet as facet
from scatterbench import models
from scatterbench.validation.report import build_report, nightly


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
    real = facet.reflection_rs_k

    def broken(c, m):
        rs, k = real(c, m)
        return -rs, k

    monkeypatch.setattr(facet, "reflection_rs_k", broken)
    with models.backend("numpy"):  # the patched function is the numpy path's (kernels: models.kernels)
        code, reg, run2, _ = nightly(hist, stamp="2026-01-02T000000Z", **kw)
    assert code != 0 and reg
    assert any("passed before and now fails" in r for r in reg)
    assert any("moved from" in r for r in reg)
    with open(os.path.join(run2, "results.json")) as fh:
        res2 = json.load(fh)
    red = [c["name"] for c in res2["checks"] if c["status"] == "fail"]
    assert any("SCATMECH" in n for n in red)
    monkeypatch.setattr(facet, "reflection_rs_k", real)

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


_DRAWING = {"plt", "figure_block", "table_block", "text_block", "store_rows", "checks_block", "Section"}


def _reachable_names(tree, start):
    """Every name used by module-level function ``start`` and the module's functions it uses."""
    funcs = {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef)}
    seen, todo, names = set(), [start], set()
    while todo:
        f = todo.pop()
        if f in seen:
            continue
        seen.add(f)
        for n in ast.walk(funcs[f]):
            if isinstance(n, ast.Name):
                names.add(n.id)
                if n.id in funcs:
                    todo.append(n.id)
    return names


def test_sections_compute_without_drawing_and_functions_are_short():
    """Each section module's compute (and every helper it uses) neither draws nor tabulates;
    no function of the report package is longer than 80 lines."""
    from scatterbench.validation.report import sections

    root = pathlib.Path(sections.__file__).parent.parent
    for spec in sections.SECTIONS:
        module = sys.modules[spec.compute.__module__]
        assert spec.render.__module__ == module.__name__, spec.id
        tree = ast.parse(pathlib.Path(module.__file__).read_text())
        drawn = _reachable_names(tree, "compute") & _DRAWING
        assert not drawn, (spec.id, drawn)
    for path in root.rglob("*.py"):
        for n in ast.walk(ast.parse(path.read_text())):
            if isinstance(n, ast.FunctionDef):
                assert n.end_lineno - n.lineno + 1 <= 80, (str(path), n.name)


def test_section_data_is_frozen_and_renders_the_reported_numbers(quick_report):
    """compute returns a frozen dataclass without drawing; render, from it alone, gives the
    numbers results.json holds (sections whose work the checks already did: cheap to redo)."""
    import matplotlib.pyplot as plt

    from scatterbench.validation.report import sections
    from scatterbench.validation.report.core import Section

    _, results, ctx = quick_report
    specs = {s.id: s for s in sections.SECTIONS}
    for sid in ("table1", "stability", "model_comparison", "scenes"):
        plt.close("all")
        data = specs[sid].compute(ctx)
        assert plt.get_fignums() == [], sid  # compute draws nothing
        assert dataclasses.is_dataclass(data) and type(data).__dataclass_params__.frozen, sid
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(data, dataclasses.fields(data)[0].name, None)
        sec = Section(sid, specs[sid].title)
        specs[sid].render(sec, data)
        reported = results["sections"][sid]
        assert json.loads(json.dumps(sec.numbers, default=float)) == reported["numbers"], sid
        assert json.loads(json.dumps(sec.tracked, default=float)) == reported["tracked"], sid


def test_stability_findings_grouped_by_model_kind_and_verdict():
    """One row per model x kind x verdict: the counts add up to every finding, the worst is the
    group's largest magnitude (with its parameters and geometry), each reason is shown once per
    group, not once per finding, and every finding stays in results.json."""
    from scatterbench.validation.report.core import Section, render_html
    from scatterbench.validation.report.sections import edge_findings
    from scatterbench.validation.studies.findings import Finding

    def finding(model, kind, value, k):
        return Finding(model, f"{model}(sigma={k})", kind, value, f"theta_i = {k} deg", {"value": value})

    findings = [finding("FacetBRDF", "energy", v, k) for k, v in enumerate((1.2, 3.5, 2.0, 1.1))]
    findings += [finding("FacetBRDF", "energy", v, k) for k, v in enumerate((5.5, -12.0), start=10)]
    findings += [finding("FacetBRDF", "nan", v, k) for k, v in enumerate((1.0, 2.0), start=20)]
    findings += [finding("CookTorranceBRDF", "energy", v, k) for k, v in enumerate((7.4, 7.5, 6.0), 30)]
    accepted = [
        {
            "model": "FacetBRDF",
            "kind": "energy",
            "condition": "0 < value < 5",
            "reason": "bounded by <H> & 'why'",
        },
        {"model": "*", "kind": "energy", "condition": "value > 7", "reason": "the paper's 4 pi"},
    ]
    d = edge_findings.summarize(findings, accepted)
    sec = Section("stability", "Stability")
    edge_findings.render(sec, d)
    page = render_html(
        {"date": "", "git_commit": "", "quick": False, "seconds": 0.0},
        [sec],
        {"n_checks": 0, "n_pass": 0, "n_finding": 0, "n_fail": 0},
    )
    groups = {(g["model"], g["kind"], g["accepted"]): g for g in sec.numbers["stability_groups"]}
    assert {k: (g["count"], g["worst value"], g["worst at"]) for k, g in groups.items()} == {
        ("FacetBRDF", "energy", "yes"): (4, 3.5, "theta_i = 1 deg"),
        ("FacetBRDF", "energy", "NO"): (2, -12.0, "theta_i = 11 deg"),
        ("FacetBRDF", "nan", "NO"): (2, 2.0, "theta_i = 21 deg"),
        ("CookTorranceBRDF", "energy", "yes"): (2, 7.5, "theta_i = 31 deg"),
        ("CookTorranceBRDF", "energy", "NO"): (1, 6.0, "theta_i = 32 deg"),
    }
    assert list(groups)[:3] == [k for k in groups if k[2] == "NO"]  # unaccepted first
    assert groups[("FacetBRDF", "energy", "yes")]["worst parameters"] == "FacetBRDF(sigma=1)"
    assert len(_cells(page, "stability_groups")) == 5 * 8  # the page shows the groups
    assert '<table data-key="stability">' not in page  # ... and not one row per finding
    for reason in ("bounded by <H> & 'why'", "the paper's 4 pi"):
        assert page.count(str(markupsafe.escape(reason))) == 1
    assert "11 findings: 6 accepted (each with its reason), 5 unaccepted, in 5 groups" in html.unescape(page)
    rows = sec.numbers["stability"]  # every finding, with its verdict and reason, in results.json
    assert len(rows) == len(findings) and sorted(r["value"] for r in rows) == sorted(
        f.value for f in findings
    )


def test_speed_section_shows_the_peer_timings_as_measured():
    """The peers' table is references/data/peer_timings.json (benchmarks/peers.py), with the run
    that measured it (date, machine, load, threads) and ratios from its own numbers; nothing
    quoted from elsewhere, no per-call figure set against a per-geometry one."""
    from scatterbench import references
    from scatterbench.validation.report.core import Section
    from scatterbench.validation.report.sections import speed
    from scatterbench.validation.studies.tradeoff import KnobResult, Point

    table = references.peer_timings()
    rows, run = speed._peers()
    assert [r["model"] for r in rows] == [t["model"] for t in table["rows"]]
    for r, t in zip(rows, table["rows"], strict=True):
        assert r["per call: peer / ours"] == t["peer_call_us"] / t["ours_call_us"]
        assert r["per geometry: peer / ours"] == t["peer_geometry_us"] / t["ours_geometry_us"]
    assert run["date"] == table["date"] and run["threads"] != "not recorded"
    assert not hasattr(speed, "QUOTED_US")
    knob = KnobResult("k", "q", "ref", [Point(1.0, 1e-3, 1e-3, 10), Point(2.0, 1e-4, 2e-3, 20)])
    throughput = (
        {
            "model": "M",
            "geometries per call": 5,
            "kernel threads": 1,
            "us per geometry (CPU)": 1.0,
            "us per geometry (wall)": 1.0,
        },
    )
    data = speed.SpeedData((knob,), ((),), 5, throughput, rows, run)
    sec = Section("speed", "Speed")
    speed.render(sec, data)
    assert sec.numbers["peers"][0]["per geometry: peer / ours"] == rows[0]["per geometry: peer / ours"]
    assert sec.numbers["peer_run"][0]["date"] == table["date"]
    shown = {b["key"]: b for b in sec.blocks if b["type"] == "table"}
    assert table["date"] in shown["peer_run"]["rows"][0] and len(shown["peers"]["rows"]) == len(rows)


def test_contributed_models_section(monkeypatch):
    """Models registered under the scatterbench.models entry points (stubbed here: a plain
    Lambertian, one that creates energy, one whose module is missing) get a section with
    their conformance results; with none installed, the section says so in one line."""
    import importlib.metadata

    group = "scatterbench.models"
    eps = [
        importlib.metadata.EntryPoint("lambert", "kit_models:Lambertian", group),
        importlib.metadata.EntryPoint("hot", "kit_models:CreatesEnergy", group),
        importlib.metadata.EntryPoint("gone", "no_such_module_xyz:Model", group),
    ]
    monkeypatch.setattr(
        importlib.metadata, "entry_points", lambda group=None: eps if group == "scatterbench.models" else []
    )
    results, page = build_report(quick=True, only=["contributed"], checks=[])
    sec = results["sections"]["contributed"]
    assert sec["error"] is None
    rows = {r["entry point"]: r for r in sec["numbers"]["contributed"]}
    assert list(rows) == ["gone", "hot", "lambert"]  # name order
    assert rows["lambert"]["verdict"] == "passed" and rows["lambert"]["fail"] == 0
    assert rows["hot"]["verdict"] == "FAILED" and rows["hot"]["fail"] >= 1
    assert (
        rows["gone"]["verdict"].startswith("not loaded: ") and "no_such_module_xyz" in rows["gone"]["verdict"]
    )
    checks = sec["numbers"]["contributed_checks"]
    assert {c["check"] for c in checks if c["entry point"] == "hot" and c["status"] == "FAIL"} == {"energy"}
    assert '<table data-key="contributed">' in page and "kit_models:CreatesEnergy" in _cells(
        page, "contributed"
    )
    assert results["summary"]["n_fail"] == 0  # shown, not judged

    monkeypatch.setattr(importlib.metadata, "entry_points", lambda group=None: [])
    results, page = build_report(quick=True, only=["contributed"], checks=[])
    assert results["sections"]["contributed"]["numbers"] == {"contributed": []}
    assert f"no contributed models installed (entry-point group {group})" in page


def test_the_comparison_text_states_the_burn_in_of_its_chains():
    """The full report's comparison burns 1000 steps in before its kept chains
    (``comparison_settings``), and its text says so; the quick one burns none and says nothing
    of it.  Fails when the settings or the text drop the burn-in."""
    from scatterbench.validation.checks.fitting import comparison_settings
    from scatterbench.validation.report.sections import model_comparison as mc

    full, quick = comparison_settings(False)["settings"], comparison_settings(True)["settings"]
    assert (full.burn, quick.burn) == (1000, 0)
    base = dict(rows=(), speckle=0.05, rows_per_file=200, all_rows=True, walkers=24, max_steps=12000, seed=3,
                chains=2, data_files=("a.csv",), scene_files=("b.toml",), scans=())  # fmt: skip
    assert "1000 steps of burn-in (not kept), then at most 12000 steps" in mc._text(
        mc.ComparisonData(**base, burn=1000)
    )
    assert "burn-in" not in mc._text(mc.ComparisonData(**base, burn=0))
