"""The documentation site: built with warnings as errors, complete, linked, and clean in a browser.

The site is built once per run (``python -m sphinx -W -b html``) from a copy of ``docs/``
in a temporary folder, so nothing generated lands in the checkout and no stale gallery
output is reused.  The doctests (docstring examples of ``models`` and ``validation`` and
the ``>>>`` examples of the user guide) run with the standard library's doctest.
"""

import doctest
import html.parser
import importlib
import os
import pkgutil
import shutil
import subprocess
import sys
import time
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

from scatterbench import models, validation

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
GENERATED = ("auto_examples", "generated", "sg_execution_times.rst", "_build")


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """``(html folder, build seconds)`` of a fresh ``-W`` build."""
    try:
        import numpydoc  # noqa: F401
        import sphinx  # noqa: F401
        import sphinx_gallery  # noqa: F401
    except ImportError:
        if os.environ.get("CI"):
            pytest.fail('the docs extra is not installed in CI (pip install ".[test]" includes it)')
        pytest.skip('the docs extra is not installed (pip install ".[docs]")')
    tmp = tmp_path_factory.mktemp("docs")
    src, out = tmp / "docs", tmp / "html"
    shutil.copytree(DOCS, src, ignore=shutil.ignore_patterns(*GENERATED))
    shutil.copy(ROOT / "pyproject.toml", tmp)  # the architecture page draws the layers from its contracts
    start = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "-b", "html", "-q", str(src), str(out)],
        capture_output=True,
        text=True,
        timeout=1200,
    )
    seconds = time.perf_counter() - start
    assert proc.returncode == 0, proc.stderr[-4000:]
    print(f"docs built in {seconds:.1f} s")
    return out, seconds


def test_build_has_no_warnings(site):
    out, seconds = site
    assert (out / "index.html").is_file()
    # a cap against a build gone wrong (a gallery example that hangs, say), far above the time
    # it takes: 37.9 s on the two shared cores here (the fixture prints it; pytest -s)
    assert seconds < 900


def test_api_reference_covers_every_public_name(site):
    out, _ = site
    generated = out / "api" / "generated"
    for cls in models.Model.registry:  # every model class has its page, with its parameter table
        page = generated / f"scatterbench.models.{cls.__name__}.html"
        assert page.is_file(), cls.__name__
        text = page.read_text(encoding="utf-8")
        if cls is not models.Sum:
            assert "Declared parameters" in text and "Corresponds to" in text, cls.__name__
        for p in cls.parameters():
            assert p.name in text, (cls.__name__, p.name)
    for name in models.__all__:
        assert (generated / f"scatterbench.models.{name}.html").is_file(), name
    pages = "".join(p.read_text(encoding="utf-8") for p in generated.glob("scatterbench.validation.*.html"))
    for name in validation.__all__:
        obj = getattr(validation, name)
        assert f'id="{obj.__module__}.{name}"' in pages, name


def test_gallery_has_six_examples_with_images(site):
    out, _ = site
    examples = sorted((out / "auto_examples").glob("plot_*.html"))
    assert len(examples) >= 6
    for page in examples:
        images = [s for s in _links(page) if s.endswith(".png") and "sphx_glr_" in s and "thumb" not in s]
        assert images, page.name
        for src in images:
            assert (page.parent / unquote(src)).is_file(), (page.name, src)


class _Refs(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.links, self.ids = [], set()

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if a.get("id"):
            self.ids.add(a["id"])
        for key in ("href", "src"):
            if a.get(key) and tag in ("a", "img", "link", "script"):
                self.links.append(a[key])


def _parse(page):
    p = _Refs()
    p.feed(page.read_text(encoding="utf-8"))
    return p


def _links(page):
    return _parse(page).links


def test_no_broken_internal_links(site):
    out, _ = site
    ids = {}
    broken = []
    checked = 0
    for page in out.rglob("*.html"):
        if page.relative_to(out).parts[0] == "_static":
            continue  # the theme's template fragments, not pages
        for link in _parse(page).links:
            parts = urlsplit(link)
            if parts.scheme or link.startswith("//"):
                continue  # external (the theme's and Sphinx's credits); the site itself is offline
            target = page if not parts.path else (page.parent / unquote(parts.path)).resolve()
            checked += 1
            if not target.exists():
                broken.append(f"{page.relative_to(out)} -> {link}")
                continue
            if parts.fragment and target.suffix == ".html":
                if target not in ids:
                    ids[target] = _parse(target).ids
                if unquote(parts.fragment) not in ids[target]:
                    broken.append(f"{page.relative_to(out)} -> {link} (no such anchor)")
    assert checked > 1000  # the whole site was walked, not an empty folder
    assert broken == []


def _modules(package):
    yield package
    for info in pkgutil.walk_packages(package.__path__, package.__name__ + "."):
        if not info.name.endswith("__main__"):  # running it would run the CLI
            yield importlib.import_module(info.name)


def test_doctests_pass():
    """Every ``>>>`` example: docstrings of models and validation, and the user guide's pages."""
    flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    runner = doctest.DocTestRunner(optionflags=flags)
    finder = doctest.DocTestFinder()
    for module in (*_modules(models), *_modules(validation)):
        for test in finder.find(module):
            runner.run(test)
    parser = doctest.DocTestParser()
    for page in sorted((DOCS / "guide").glob("*.md")):
        text = page.read_text(encoding="utf-8")
        runner.run(parser.get_doctest(text, {}, page.name, str(page), 0))
    result = runner.summarize(verbose=False)
    assert result.attempted >= 10  # the guide's examples at least: the run is not vacuous
    assert result.failed == 0


def test_site_in_chromium(site):
    from test_report_browser import ARGS, CHROMIUM, _need_browser

    _need_browser()
    from playwright.sync_api import sync_playwright

    out, _ = site
    pages = [
        "index.html",
        "guide/conventions.html",
        "api/models.html",
        "api/generated/scatterbench.models.FacetBRDF.html",
        "auto_examples/index.html",
        *(f"auto_examples/{p.name}" for p in sorted((out / "auto_examples").glob("plot_*.html"))),
    ]
    problems = []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        page = browser.new_page(viewport={"width": 1300, "height": 1000})
        errors, failed = [], []
        page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
        page.on("pageerror", lambda e: errors.append(str(e)))
        # only the site's own files: external requests (none are needed) are not the site's
        page.on("requestfailed", lambda r: failed.append(r.url) if r.url.startswith("file:") else None)
        for name in pages:
            errors.clear()
            failed.clear()
            page.goto((out / name).as_uri())
            page.wait_for_load_state("load")
            broken = page.evaluate(
                "Array.from(document.images).filter(i => !i.complete || i.naturalWidth === 0).map(i => i.src)"
            )
            n_images = page.evaluate("document.images.length")
            if errors or failed or broken:
                problems.append((name, errors[:], failed[:], broken))
            if name.startswith("auto_examples/plot_"):
                assert n_images >= 1, name
        browser.close()
    assert problems == []
