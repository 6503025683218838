"""The design card's layout rules: one import namespace, models never import validation,
references holds data."""

import os
import shutil
import subprocess
import sys
import textwrap
import zipfile

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_models_do_not_import_validation():
    code = (
        "import sys, scatterbench.models; "
        "print([k for k in sys.modules if k.startswith('scatterbench.validation')])"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert r.stdout.strip() == "[]"


def test_reference_files_carry_provenance():
    from scatterbench import references

    folder = os.path.dirname(references.data_path("x"))
    for name in os.listdir(folder):
        if name.endswith(".csv"):
            assert references.provenance(name).strip(), name


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    """A wheel built from this checkout's files, as ``pip install .`` builds one (from a copy:
    setuptools leaves its build folder in the tree it builds)."""
    src, out = tmp_path_factory.mktemp("src"), tmp_path_factory.mktemp("wheel")
    junk = shutil.ignore_patterns("__pycache__", "build", "*.egg-info", "_build_commit.txt")
    for name in ("namespace", "models", "validation", "references"):
        shutil.copytree(os.path.join(ROOT, name), src / name, ignore=junk)
    for name in ("pyproject.toml", "setup.py", "README.md"):
        shutil.copy(os.path.join(ROOT, name), src / name)
    pip = [sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "-w", str(out)]
    # offline where the installed setuptools can build it (with wheel), else isolated
    for extra in (["--no-build-isolation"], []):
        r = subprocess.run([*pip, *extra, str(src)], capture_output=True, text=True, timeout=600)
        if r.returncode == 0:
            (path,) = out.glob("scatterbench-*.whl")
            return path
    pytest.fail(f"pip wheel failed: {r.stderr[-2000:]}")


def test_the_distribution_installs_one_top_level_name(wheel):
    with zipfile.ZipFile(wheel) as zf:
        names = zf.namelist()
        tops = {n.split("/")[0] for n in names if not n.split("/")[0].endswith(".dist-info")}
        (info,) = {n.split("/")[0] for n in names if n.split("/")[0].endswith(".dist-info")}
        top_level = zf.read(f"{info}/top_level.txt").decode().split()
    assert tops == {"scatterbench"}, tops
    assert top_level == ["scatterbench"]
    # the three folders are there under it, with their data, and the generator scripts are not
    for part in ("models/base.py", "validation/cli/__init__.py", "references/data/presets.toml"):
        assert f"scatterbench/{part}" in names, part
    assert not [n for n in names if "/scripts/" in n]


# a project of a user's own, named as scientific code often names its modules
_USER_MODELS = '''
"""The user's own models: a plain Lambertian, in a module called models."""
import math

import numpy as np


class MyBRDF:
    def __init__(self, roughness=0.0):
        self.roughness = roughness

    def mueller(self, theta_i, theta_r, phi_r):
        shape = np.broadcast_shapes(np.shape(theta_i), np.shape(theta_r), np.shape(phi_r))
        M = np.zeros(shape + (4, 4))
        M[..., 0, 0] = 0.8 / math.pi
        return M
'''
_USER_VALIDATION = '''
"""The user's own validation helpers."""
ALBEDO = 0.8
'''
# the README's recipe ("Validate your own model"), with the user's modules named as above
_USER_TEST = """
from models import MyBRDF
from validation import ALBEDO
from scatterbench.validation.testing import parametrize_with_checks


@parametrize_with_checks([MyBRDF(), MyBRDF(roughness=0.5)])
def test_conformance(model, check):
    check(model)


def test_own_modules_are_the_user_s():
    assert ALBEDO == 0.8
"""


def test_a_user_s_own_models_and_validation_modules_do_not_shadow_the_kit(tmp_path):
    """A project with its own ``models.py`` and ``validation.py`` runs the README's kit recipe
    with ``python -m pytest`` (the project's folder first on sys.path) and passes."""
    for name, text in (
        ("models.py", _USER_MODELS),
        ("validation.py", _USER_VALIDATION),
        ("test_my_brdf.py", _USER_TEST),
    ):
        (tmp_path / name).write_text(textwrap.dedent(text))
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    r = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "test_my_brdf.py"],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-2000:]
    # one test per (model, check), and the user's own module test
    assert " passed" in r.stdout and " failed" not in r.stdout


# the lint-imports command (its console script need not be on PATH)
_LINT = "import sys; from importlinter.cli import lint_imports_command; sys.exit(lint_imports_command())"


def test_the_import_contract_holds(wheel, tmp_path):
    """pyproject.toml's import-linter contracts (the layers of validation and models, references
    as data, no cycle between the members of any package) hold for the built package: an
    import that breaks a layer or closes a cycle fails the test command."""
    pytest.importorskip("importlinter")
    site = tmp_path / "site"
    with zipfile.ZipFile(wheel) as zf:
        zf.extractall(site)
    env = {**os.environ, "PYTHONPATH": str(site)}
    r = subprocess.run(
        [sys.executable, "-c", _LINT, "--no-cache", os.path.join(ROOT, "pyproject.toml")],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert r.returncode == 0, r.stdout[-6000:] + r.stderr[-2000:]
    assert "broken" in r.stdout and " 0 broken" in r.stdout
