"""Build hook: record the git commit of the checkout a wheel is built from.

``pip install .`` copies the package into site-packages, where ``git`` can no
longer say which commit the code came from; the report's provenance reads the
commit written here (``validation/_build_commit.txt``) instead.  Everything else
about the build is declared in pyproject.toml.
"""

import os
import subprocess

from setuptools import setup
from setuptools.command.build_py import build_py


class BuildPyWithCommit(build_py):
    def run(self):
        super().run()
        commit = _git_commit(os.path.dirname(os.path.abspath(__file__)))
        if commit and not self.dry_run:
            target = os.path.join(self.build_lib, "validation", "_build_commit.txt")
            os.makedirs(os.path.dirname(target), exist_ok=True)
            with open(target, "w") as fh:
                fh.write(commit + "\n")


def _git_commit(folder):
    try:
        r = subprocess.run(
            ["git", "-C", folder, "describe", "--always", "--dirty", "--abbrev=12"],
            capture_output=True,
            text=True,
            timeout=10,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return r.stdout.strip() if r.returncode == 0 else None


setup(cmdclass={"build_py": BuildPyWithCommit})
