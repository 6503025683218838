"""Another checkout's scatterbench beside this one, for before/after benchmarks.

The package's import names (``scatterbench.models``, ...) map onto the repository's folders
only through an installation (pyproject.toml's package-dir), so a checkout on ``PYTHONPATH``
is not importable by itself.  :func:`environment` gives the environment of a child process
that imports ``root``'s code: the running environment where its scatterbench is ``root``'s
(an editable install of this checkout); otherwise ``root`` installed without dependencies into
a folder of its own under the temporary directory (once per tree and state of its files; where
it cannot be built, its packages linked there, :func:`linked`) and put first on ``PYTHONPATH``; a tree from before the one namespace (top-level ``models``, no
``namespace/``) is put on ``PYTHONPATH`` itself.  A child imports the models with
:data:`IMPORT_MODELS`, which works in both layouts.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
import tomllib

#: the import a child process runs: ``models`` bound in either layout
IMPORT_MODELS = "try:\n    from scatterbench import models\nexcept ImportError:\n    import models\n"

_SOURCES = ("namespace", "models", "validation", "references")


def _running_root():
    """The checkout the running environment imports scatterbench from, or ``None``."""
    try:
        import scatterbench.models as m
    except ImportError:
        return None
    return os.path.dirname(os.path.dirname(os.path.realpath(m.__file__)))


def _state(root):
    """A digest of ``root``'s path and its package files' names, sizes and times."""
    h = hashlib.sha1(os.path.realpath(root).encode())
    for top in _SOURCES + ("pyproject.toml", "setup.py"):
        path = os.path.join(root, top)
        for dirpath, dirnames, files in os.walk(path) if os.path.isdir(path) else [("", [], [path])]:
            dirnames.sort()
            for f in sorted(files):
                st = os.stat(os.path.join(dirpath, f))
                h.update(f"{dirpath}/{f}:{st.st_size}:{st.st_mtime_ns}".encode())
    return h.hexdigest()[:16]


def _installed(root):
    """``root`` installed (no dependencies) into a folder of its own; the folder."""
    target = os.path.join(tempfile.gettempdir(), f"scatterbench-checkout-{_state(root)}")
    if not os.path.isdir(os.path.join(target, "scatterbench")):
        pip = [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--target", target]
        # offline where the installed setuptools can build it (with wheel), else isolated
        for extra in (["--no-build-isolation"], []):
            r = subprocess.run([*pip, *extra, root], capture_output=True, text=True)
            if r.returncode == 0:
                break
        else:  # no build (setuptools < 70.1 without wheel) and no index to fetch one from
            shutil.rmtree(target, ignore_errors=True)
            linked(root, target)
    return target


def linked(root, target=None):
    """``root``'s packages importable from ``target`` (default: a new temporary folder) without
    building them: pyproject.toml's package-dir as links, the top package's files in a folder
    of its own and each subpackage's folder linked in it.  Returns ``target``, for
    ``PYTHONPATH``; the links follow ``root``'s files as they change."""
    root = os.path.realpath(root)
    with open(os.path.join(root, "pyproject.toml"), "rb") as f:
        dirs = tomllib.load(f)["tool"]["setuptools"]["package-dir"]
    target = target or tempfile.mkdtemp(prefix="scatterbench-links-")
    top = os.path.join(target, "scatterbench")
    os.makedirs(top)
    src = os.path.join(root, dirs["scatterbench"])
    for name in os.listdir(src):
        os.symlink(os.path.join(src, name), os.path.join(top, name))
    for package, folder in dirs.items():
        if package != "scatterbench":
            os.symlink(os.path.join(root, folder), os.path.join(target, *package.split(".")))
    return target


def environment(root) -> dict:
    """The environment of a child process that imports ``root``'s scatterbench."""
    root = os.path.realpath(root)
    if not os.path.isdir(os.path.join(root, "namespace")):  # before the one namespace
        return dict(os.environ, PYTHONPATH=root)
    if _running_root() == root:
        return dict(os.environ)
    return dict(os.environ, PYTHONPATH=_installed(root))
