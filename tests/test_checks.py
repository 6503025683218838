"""The check registry: one declaration feeds ``validate``, the report and this suite.

* every registered quick check does not fail (read from the quick report built once);
* ``validate --quick`` judges exactly the checks the quick report judges;
* every finding-type check fails when its input violates its stated condition;
* a limit check fails above its tolerance, on NaN, and when it raises.
"""

import dataclasses
import json
import math

import pytest

from scatterbench.validation.checks import registry
from scatterbench.validation.checks.registry import (
    CheckContext,
    CheckSpec,
    judge,
    registered,
    run_checks,
)
from scatterbench.validation.checks.table1 import compute_table1
from scatterbench.validation.cli import main
from scatterbench.validation.cli import validate as validate_cmd
from scatterbench.validation.studies.findings import Finding

QUICK = registered(quick=True)


# ----------------------------------------------------------------------------- every quick check
@pytest.mark.parametrize("spec", QUICK, ids=[s.id for s in QUICK])
def test_registered_quick_check_does_not_fail(quick_report, spec):
    _, results, _ = quick_report
    mine = [c for c in results["checks"] if c["id"] == spec.id]
    assert mine, f"{spec.id} returned nothing"
    failed = [f"{c['name']}: {c['measured']} vs {c['op']} {c['tolerance']} ({c['detail']})" for c in mine]
    assert all(c["status"] != "fail" for c in mine), failed
    assert all(c["paper"] == spec.paper and c["slow"] is False for c in mine)


def test_quick_validate_and_quick_report_judge_the_same_checks(quick_report, tmp_path, capsys):
    _, results, ctx = quick_report
    path = tmp_path / "checks.json"
    assert validate_cmd.run(quick=True, json_path=str(path), ctx=ctx) == 0
    out = capsys.readouterr().out
    doc = json.loads(path.read_text(), parse_constant=lambda c: pytest.fail(f"non-strict JSON: {c}"))
    assert [c["name"] for c in doc["checks"]] == [c["name"] for c in results["checks"]]
    assert doc["summary"] == results["summary"] and doc["quick"] is True
    for c in doc["checks"]:
        assert set(c) >= {
            "id",
            "name",
            "paper",
            "measured",
            "tolerance",
            "status",
            "detail",
            "fails_if",
            "slow",
        }
        assert (c["fails_if"] is not None) == (c["name"] in registry.select([c["id"]])[0].findings)
    # the table, the findings with their failure conditions, and the text blocks after it
    assert "SCATMECH: SubsurfaceFacetBRDF Mueller" in out and "FINDING" in out and " FAIL" not in out
    assert out.count("fails if: ") == sum(c["fails_if"] is not None for c in doc["checks"])
    assert "Table I" in out and "within rounding" in out and "Seed 003 Fig. 1" in out


def test_quick_report_shows_the_failure_conditions(quick_report):
    out, results, _ = quick_report
    page = (out / "report.html").read_text()
    shown = [c for c in results["checks"] if c["fails_if"]]
    assert shown and all(c["status"] in ("pass", "finding") for c in shown)
    assert page.count("fails if: ") == len(shown)
    skipped = [s.id for s in registered() if s.slow]
    assert skipped and all(i in page for i in skipped)  # the slow checks a quick run leaves out, named


# ----------------------------------------------------------------------------- findings can fail
def _mc(*broken):
    """mc_energy_samples-shaped input: both findings hold; ``broken`` entries replace some."""
    s = {("exact", sg, t): (0.9, 0.01) for sg in (0.5, 2.0) for t in (0.0, 60.0, 85.0)}
    s["paper", 2.0, 85.0] = (1.3, 0.01)
    s["single", 0.5, 0.0] = (0.5, 0.01)
    s["single+diffuse", 0.5, 0.0] = (1.1, 0.01)
    return {"samples": {**s, **dict(broken)}}


def _table1_rows(unresolved):
    rows = compute_table1()[0]
    bad = dataclasses.replace(rows[2], within_rounding=False, independent_agrees=not unresolved)
    return [bad if i == 2 else r for i, r in enumerate(rows)]


_VARNISH = [(0.03, "published", 0.0, 2.0, 1e-6, 0.96), (0.03, "refracted", 0.0, 0.9, 1e-6, 0.96)]
_COLLIMATED = {1e2: 5e-3, 1e3: 5e-5, 1e4: 5e-7}


#: (check id, finding name) -> (inputs under which it holds, inputs that violate its condition)
MUTATIONS = {
    ("seed000.check_table1", "Table I: entries within the printed rounding"): (
        lambda: {"rows": _table1_rows(unresolved=False)},
        lambda: {"rows": _table1_rows(unresolved=True)},
    ),
    ("seed000.check_energy", "energy: largest integrated reflectance (no-shadowing model)"): (
        lambda: {"samples": [("m", 1.5, 1.1, 1e-5, 1.2, None)]},
        lambda: {"samples": [("m", 1.5, 1.1, 1e-5, 0.95, None)]},
    ),
    ("seed001.check_fresnel", "seed001: Eq. 15-16 as printed, max |F - F_true|"): (
        lambda: {"printed": {"printed": (186.0, ""), "unsquared": (0.37, "")}},
        lambda: {"printed": {"printed": (186.0, ""), "unsquared": (0.0, "")}},
    ),
    ("seed001.check_energy", "seed001: published Cook-Torrance albedo (iron, m = 0.03)"): (
        lambda: {"published": {17.0: 7.4, 63.0: 7.1}, "energy": [(0.03, 1.0, 0.0, 0.9, 1e-6)]},
        lambda: {"published": {17.0: 7.4, 63.0: 0.99}, "energy": [(0.03, 1.0, 0.0, 0.9, 1e-6)]},
    ),
    ("seed001.check_varnish_energy", "seed001: energy-normalized Eq. 24 albedo, perfect conductor"): (
        lambda: {"rows": _VARNISH},
        lambda: {"rows": _VARNISH[:1] + [(0.03, "refracted", 0.0, 1.0, 1e-6, 0.96)]},
    ),
    ("seed001.check_point_source", "seed001: point-source non-reciprocity (d = 10 R)"): (
        lambda: {
            "collimated": _COLLIMATED,
            "shifted": _COLLIMATED,
            "nonreciprocity": {10.0: 0.5, 100.0: 0.01},
        },
        lambda: {
            "collimated": _COLLIMATED,
            "shifted": _COLLIMATED,
            "nonreciprocity": {10.0: 0.5, 100.0: 0.6},
        },
    ),
    ("seed001.check_cauchy", "seed001: Eq. 25 weight integrated over the plane"): (
        lambda: {"integrals": {100.0: (9.2, 0.99), 1000.0: (13.8, 0.999)}},
        lambda: {"integrals": {100.0: (1.0, 0.99), 1000.0: (1.0, 0.999)}},
    ),
    ("seed003.check_printed_eq22", "Eq. 22 as printed (1/(2 pi)): albedo at rho=1"): (
        lambda: {"albedo": 0.59},
        lambda: {"albedo": 1.0},
    ),
    ("seed003.check_btdf_paper_normalization", "FacetBTDF Eq. 37 normalization: transmittance > 1"): (
        lambda: {"transmittances": (1.05, 0.92)},
        lambda: {"transmittances": (1.05, 1.01)},
    ),
    ("seed003.check_mc_energy", "MC energy: rho=1, paper surface term, rms 2, 85 deg"): (
        lambda: _mc(),
        lambda: _mc((("exact", 2.0, 85.0), (1.1, 0.01))),
    ),
    ("seed003.check_mc_energy", "MC energy: single + diffuse at rho=1 (terms overlap)"): (
        lambda: _mc(),
        lambda: _mc((("single", 0.5, 0.0), (1.1, 0.01))),
    ),
}
FINDINGS = [(s.id, name) for s in registered() for name in s.findings]


def _result(spec_id, name, inputs):
    spec = registry.select([spec_id])[0]
    out = spec.func(CheckContext(), **inputs)
    (r,) = [c for c in (out if isinstance(out, list) else [out]) if c.name == name]
    return r


def test_every_finding_check_has_a_mutation():
    assert sorted(MUTATIONS) == sorted(FINDINGS)


@pytest.mark.parametrize("spec_id, name", FINDINGS, ids=[f"{i}: {n}" for i, n in FINDINGS])
def test_finding_check_fails_when_its_condition_is_violated(spec_id, name):
    holds, broken = MUTATIONS[spec_id, name]
    r = _result(spec_id, name, holds())
    assert r.status == "finding" and r.fails_if, r
    r = _result(spec_id, name, broken())
    assert r.status == "fail", r


# ----------------------------------------------------------------------------- the judge itself
def test_limit_check_goes_red_above_its_tolerance_and_on_nan():
    assert judge("x", 1e-13, 1e-12).status == "pass"
    assert judge("x", 1e-12, 1e-12).status == "pass"  # the limit is inclusive for "<="
    assert judge("x", 2e-12, 1e-12).status == "fail"
    assert judge("x", math.nan, 1e-12).status == "fail"
    assert judge("x", math.inf, math.inf).status == "fail"
    assert judge("x", 11.0, 10.0, op=">").status == "pass"
    assert judge("x", 10.0, 10.0, op=">").status == "fail"
    # a finding with a NaN measurement is a failure, not a finding
    assert judge("x", math.nan, 1.0, finding=Finding(fails=False, fails_if="never")).status == "fail"
    with pytest.raises(ValueError, match="op"):
        judge("x", 1.0, 1.0, op="=")


def test_a_finding_without_its_verdict_is_refused():
    """One Finding type serves the checks and the stability sweep, whose findings carry no
    verdict (accepted_findings.toml gives it): judged as a check's, one would count as holding
    (``fails`` None is false), so the judge refuses it."""
    swept = Finding("FacetBRDF", "FacetBRDF()", "energy", 1.2, "theta_i = 0 deg")
    for finding in (swept, Finding(fails=False), Finding(fails_if="never")):
        with pytest.raises(ValueError, match="verdict"):
            judge("x", 2.0, 1.0, finding=finding)
    assert judge("x", 2.0, 1.0, finding=Finding(fails=False, fails_if="never")).status == "finding"
    assert judge("x", 2.0, 1.0, finding=Finding(fails=True, fails_if="always")).status == "fail"


def test_a_real_limit_check_goes_red_on_a_broken_input():
    spec = registry.select(["seed000.check_energy"])[0]
    ok = [("m", 0.0, 0.9, 1e-5, 1.0, 0.9)]
    broken = [("m", 0.0, 0.9, 1e-5, 1.0, 0.9 + 2e-4)]  # the slope-space prediction off by 2e-4
    assert spec.func(CheckContext(), samples=ok)[0].status == "pass"
    assert spec.func(CheckContext(), samples=broken)[0].status == "fail"


def _spec(cid, fn, findings=(), slow=False):
    return CheckSpec(cid, fn, "test", slow, findings)


def test_run_checks_names_raising_broken_and_undeclared_checks():
    def raises(ctx):
        raise ZeroDivisionError("boom")

    def undeclared(ctx):
        return judge("u", 2.0, 1.0, finding=Finding(fails=False, fails_if="never"))

    def missing(ctx):
        return judge("m", 0.0, 1.0)

    specs = [
        _spec("t.raises", raises),
        _spec("t.undeclared", undeclared),
        _spec("t.missing", missing, ("m",)),
    ]
    out = run_checks(specs, CheckContext())
    assert [(r.name, r.status, r.id) for r in out] == [
        ("raises", "fail", "t.raises"),
        ("u", "fail", "t.undeclared"),
        ("m", "fail", "t.missing"),
    ]
    assert "ZeroDivisionError: boom" in out[0].detail and "undeclared finding" in out[1].detail


def test_context_computes_once():
    ctx = CheckContext()
    calls = []

    def f(x, y=1):
        calls.append(x)
        return x + y

    assert ctx.compute(f, 1, y=2) == ctx.compute(f, 1, y=2) == 3
    assert ctx.compute(f, 2) == 3 and calls == [1, 2]


# ----------------------------------------------------------------------------- the command
def test_validate_command_exit_codes_and_strict_json(monkeypatch, tmp_path, capsys):
    checks = {
        "t.ok": _spec("t.ok", lambda ctx: judge("ok", 0.5, 1.0)),
        "t.slow": _spec("t.slow", lambda ctx: judge("slow nan", math.nan, 1.0), slow=True),
    }
    monkeypatch.setattr(registry, "_CHECKS", checks)
    monkeypatch.setattr(registry, "_TEXTS", [])
    path = tmp_path / "out" / "v.json"
    assert main(["validate", "--quick", "--json", str(path)]) == 0
    doc = json.loads(path.read_text())
    assert [c["name"] for c in doc["checks"]] == ["ok"] and doc["quick"] is True
    assert main(["validate", "--json", str(path)]) == 1
    text = path.read_text()
    assert "NaN" not in text and "Infinity" not in text
    doc = json.loads(text)
    assert doc["checks"][1] == {
        "id": "t.slow",
        "name": "slow nan",
        "paper": "test",
        "measured": None,
        "tolerance": 1.0,
        "op": "<=",
        "status": "fail",
        "detail": "",
        "fails_if": None,
        "slow": True,
    }
    assert doc["summary"] == {"n_checks": 2, "n_pass": 1, "n_finding": 0, "n_fail": 1}
    assert "2 checks: 1 pass, 0 findings, 1 fail" in capsys.readouterr().out
    assert not list((tmp_path / "out").glob(".tmp-*"))  # written atomically, nothing left over


def test_report_section_that_raises_is_a_failed_machinery_entry(monkeypatch):
    import scatterbench.validation.report.build as build
    from scatterbench.validation.report import build_report, sections
    from scatterbench.validation.report.core import SectionSpec

    def broken(ctx):
        raise RuntimeError("drawing failed")

    summary, provenance = sections.SECTIONS[0], sections.SECTIONS[-1]
    specs = [summary, SectionSpec("scenes", "Scenes", broken, lambda s, d: None), provenance]
    monkeypatch.setattr(build, "SECTIONS", specs)
    results, _ = build_report(quick=True, checks=[])
    (c,) = results["checks"]
    assert c["name"] == "report section 'scenes' computed" and c["status"] == "fail"
    assert c["id"] == "report.section_scenes" and c["paper"] == "report machinery"
    assert "drawing failed" in c["detail"] and results["summary"]["n_fail"] == 1
    assert results["sections"]["scenes"]["error"] == "RuntimeError: drawing failed"
