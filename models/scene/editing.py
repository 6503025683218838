"""Dotted-key editing of a scene file's data (for fits and sweeps).

A dotted key names a value of the file: ``substrate.sigma``, ``coating.index``,
``coating.roughness.sigma``, ``substrate.index[1]`` (k of an ``[n, k]`` index),
``substrate.film.layers[0].thickness_nm`` (a key of a table in an array of tables).  These
functions work on the parsed TOML dict; the scene validates the edited dict again.
"""

from __future__ import annotations

import copy

from .schema import SceneError

__all__ = ["get_value", "with_values"]


def get_value(data: dict, key: str, path: str = "<scene>"):
    """The value at a dotted ``key`` of ``data`` (``path`` names the file in errors)."""
    node, last, idx = _locate(data, key, path)
    v = copy.deepcopy(node[last])
    return v[idx] if idx is not None else v


def with_values(data: dict, values: dict, path: str = "<scene>") -> dict:
    """A copy of ``data`` with the dotted keys of ``values`` set (``data`` is untouched)."""
    out = copy.deepcopy(data)
    for key, value in values.items():
        node, last, idx = _locate(out, key, path)
        if idx is None:
            node[last] = value
        else:
            # an index given as a plain n gains its k (0) when k is set
            cur = list(node[last]) if isinstance(node[last], list) else [node[last], 0.0]
            cur[idx] = value
            node[last] = cur
    return out


def _locate(data, key, path):
    """``(table, name, index)`` of a dotted key: the table holding it, its name there, and the
    list index of a ``key[i]`` form (None otherwise)."""
    idx = None
    if key.endswith("]") and "[" in key.rpartition(".")[2]:
        key, _, rest = key.rpartition("[")
        try:
            idx = int(rest[:-1])
        except ValueError as exc:
            raise SceneError(f"{path}: {key}: bad index in {rest!r}") from exc
    parts = key.split(".")
    node = data
    for p in parts[:-1]:
        name, _, pos = p.partition("[")
        if pos:  # a table in an array of tables: substrate.film.layers[0].thickness_nm
            items = node.get(name)
            try:
                node = items[int(pos.removesuffix("]"))] if isinstance(items, list) else None
            except (ValueError, IndexError):
                node = None
        else:
            node = node.get(p)
        if not isinstance(node, dict):
            raise SceneError(f"{path}: {key}: no table [{p}] in the scene")
    if parts[-1] not in node:
        raise SceneError(f"{path}: {key}: not set in the scene")
    return node, parts[-1], idx
