"""Text of input errors: a bad value as a message shows it, a position in a file, numbers
and UTF-8 text read from files.

A leaf module: the parameter checks (:mod:`scatterbench.models.params`, the polarization
states), the scene files (:mod:`scatterbench.models.scene`) and the harness's own readers
and flags (data, fit specifications, the command line) all phrase their errors with it.
"""

from __future__ import annotations

import math
import re
import sys

__all__ = ["shown", "is_number", "where", "long_digits", "read_utf8"]


def shown(value, width=60):
    """``repr(value)`` cut to ``width`` characters (``...`` at the end when cut), for the
    ``got ...`` part of an error message about a file's or a flag's value."""
    text = repr(value)
    return text if len(text) <= width else text[: width - 3] + "..."


def is_number(value) -> bool:
    """True for a finite real number a file can give (an int or a float, not a bool) that a
    float can hold (an integer past the largest float overflows, and is no number here)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def where(text: str, offset: int):
    """``(line, column)``, both 1-based, of a character offset of ``text``."""
    return text.count("\n", 0, offset) + 1, offset - text.rfind("\n", 0, offset)


def long_digits(text: str):
    """The regular-expression match of the first run of more digits than Python converts
    to an integer (``sys.get_int_max_str_digits()``), or ``None``: what a parser's bare
    ``ValueError`` about such an integer was about, so that errors can say where it is."""
    limit = sys.get_int_max_str_digits()
    return re.search(rf"\d{{{limit + 1},}}", text) if limit else None


def read_utf8(path: str, what: str, error):
    """The UTF-8 text of the file ``path`` (a byte-order mark dropped).  A file that cannot
    be read or is not UTF-8 raises ``error(at, message)``, ``at`` the ``(line, column)`` of
    the first bad byte (``None`` for a file not read); ``what`` names the file in the
    message ("scene file", "data file")."""
    try:
        with open(path, "rb") as fh:
            raw = fh.read()
    except OSError as exc:
        raise error(None, f"cannot read the {what} ({exc.strerror})") from exc
    body = raw[3:] if raw.startswith(b"\xef\xbb\xbf") else raw
    try:
        return body.decode("utf-8")
    except UnicodeDecodeError as exc:
        text = body[: exc.start].decode("utf-8")
        raise error(
            where(text, len(text)), f"not UTF-8 text (byte 0x{body[exc.start]:02x}); save the {what} as UTF-8"
        ) from None
