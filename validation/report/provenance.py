"""Which code produced a report: the git commit, however scatterbench was installed."""

from __future__ import annotations

import os
import subprocess

__all__ = ["git_commit", "describe"]

_PACKAGE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def describe(folder):
    """``git describe --always --dirty`` of ``folder``, or ``None`` outside a checkout.
    Imports nothing from scatterbench: setup.py loads this file by path at build time."""
    try:
        r = subprocess.run(
            ["git", "-C", folder, "describe", "--always", "--dirty", "--abbrev=12"],
            capture_output=True,
            text=True,
            timeout=5,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return r.stdout.strip() if r.returncode == 0 and r.stdout.strip() else None


def git_commit() -> str:
    """The commit of the running code: from git when the package runs from a checkout
    (source tree or editable install; ``-dirty`` marks uncommitted changes), else the
    commit recorded when the package was built from a checkout (setup.py), else
    "unknown"."""
    here = describe(_PACKAGE)
    if here:
        return here
    try:
        with open(os.path.join(_PACKAGE, "_build_commit.txt"), encoding="utf-8") as fh:
            recorded = fh.read().strip()
    except OSError:
        recorded = ""
    return f"{recorded} (recorded at install)" if recorded else "unknown"
