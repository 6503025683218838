"""Build hooks: the package list of the one namespace, and the git commit of the checkout.

* ``scatterbench`` maps its subpackages onto the repository's top-level folders
  (pyproject.toml's package-dir): every folder with an ``__init__.py`` under ``models/``,
  ``validation/`` and ``references/`` is ``scatterbench.<its dotted path>``, found here so
  that a new subpackage cannot be left out of the wheel.
* ``pip install .`` copies the package into site-packages, where ``git`` can no
  longer say which commit the code came from; the report's provenance reads the
  commit written here (``scatterbench/validation/_build_commit.txt``) instead.

Everything else about the build is declared in pyproject.toml.
"""

import importlib.util
import os

from setuptools import find_packages, setup
from setuptools.command.build_py import build_py

HERE = os.path.dirname(os.path.abspath(__file__))
FOLDERS = ("models", "validation", "references")


def _packages():
    out = ["scatterbench"]
    for top in FOLDERS:
        out += [f"scatterbench.{top}"]
        out += [f"scatterbench.{top}.{sub}" for sub in find_packages(os.path.join(HERE, top))]
    return out


def _provenance():
    # the report's own module, loaded by path: the package itself (numpy, ...) need not be
    # importable in an isolated build environment
    spec = importlib.util.spec_from_file_location(
        "_sb_provenance", os.path.join(HERE, "validation", "report", "provenance.py")
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class BuildPyWithCommit(build_py):
    def run(self):
        super().run()
        commit = _provenance().describe(HERE)
        if commit and not self.dry_run:
            target = os.path.join(self.build_lib, "scatterbench", "validation", "_build_commit.txt")
            os.makedirs(os.path.dirname(target), exist_ok=True)
            with open(target, "w") as fh:
                fh.write(commit + "\n")


setup(packages=_packages(), cmdclass={"build_py": BuildPyWithCommit})
