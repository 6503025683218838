"""The quick report opened in a real browser (headless Debian Chromium driven by Playwright).

Skipped on a developer machine without Chromium or Playwright; in CI (CI set) their
absence is a failure, since the README test command installs them (scripts/install_browser.sh).
"""

import json
import os
import shutil

import pytest

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def _need_browser():
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        if os.environ.get("CI"):
            pytest.fail("playwright is not installed in CI")
        pytest.skip("playwright is not installed")
    if not CHROMIUM:
        if os.environ.get("CI"):
            pytest.fail("Chromium is not installed in CI (scripts/install_browser.sh installs it)")
        pytest.skip("no Chromium on this machine")


def test_quick_report_in_chromium(request):
    _need_browser()
    from playwright.sync_api import sync_playwright

    out, results, _ = request.getfixturevalue("quick_report")  # tests/conftest.py, built once
    shots = os.path.join(os.path.dirname(__file__), "..", "reports", "screenshots")
    os.makedirs(shots, exist_ok=True)
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        page = browser.new_page(viewport={"width": 1300, "height": 1800})
        errors = []
        page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
        page.on("pageerror", lambda e: errors.append(str(e)))
        failed = []
        page.on("requestfailed", lambda r: failed.append(r.url))
        page.goto((out / "report.html").as_uri())
        page.wait_for_load_state("load")
        ids = page.eval_on_selector_all("section[data-section]", "els => els.map(e => e.id)")
        broken = page.evaluate(
            "Array.from(document.images).filter(i => !i.complete || i.naturalWidth === 0).length"
        )
        n_images = page.evaluate("document.images.length")
        page.screenshot(path=os.path.join(shots, "report.png"), full_page=True)
        browser.close()
    assert errors == [] and failed == []
    assert set(ids) == set(results["sections"])  # every section computed is on the page
    for sid in (
        "summary",
        "table1",
        "seed000",
        "conservation",
        "scatmech",
        "seed003_fig1",
        "seed003_presets",
        "seed001",
        "uncertainty",
        "model_comparison",
        "speed",
        "stability",
        "scenes",
        "provenance",
    ):
        assert sid in ids
    assert n_images >= 6 and broken == 0
    assert not [s for s in results["sections"].values() if s["error"]]
    json.dumps(results)
