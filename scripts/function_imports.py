"""Count the import statements inside function bodies of the installed package's folders.

    python scripts/function_imports.py [TREE] [-v]

The layers contract (pyproject's [tool.importlinter]) sees only module-level imports, so an
import inside a function could hide a cycle from it; the package allows one only for an
optional or heavy dependency, with a comment.  This prints how many remain, and with -v the
internal ones (each should be a numba kernel module loaded on first use).
"""

import ast
import pathlib
import sys

FOLDERS = ("models", "validation", "references", "namespace")
INTERNAL = {"models", "validation", "references", "scatterbench"}


def function_imports(root):
    """(path, line, module, internal) for each import statement inside a function."""
    seen = set()
    for top in FOLDERS:
        for path in sorted((root / top).rglob("*.py")):
            for fn in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    for node in ast.walk(fn):
                        key = (path, getattr(node, "lineno", None))
                        if isinstance(node, (ast.Import, ast.ImportFrom)) and key not in seen:
                            seen.add(key)
                            yield _row(root, path, node)


def _row(root, path, node):
    if isinstance(node, ast.ImportFrom):
        module = "." * node.level + (node.module or "")
        internal = node.level > 0 or (node.module or "").split(".")[0] in INTERNAL
    else:
        module = node.names[0].name
        internal = module.split(".")[0] in INTERNAL
    return str(path.relative_to(root)), node.lineno, module, internal


def main(argv):
    root = pathlib.Path(next((a for a in argv if a != "-v"), "."))
    rows = list(function_imports(root))
    print(f"imports inside functions: {len(rows)} ({sum(r[3] for r in rows)} internal)")
    for path, line, module, internal in rows:
        if internal and "-v" in argv:
            print(f"  {path}:{line}  {module}")


if __name__ == "__main__":
    main(sys.argv[1:])
