"""Reading a TOML input file with bounds: its size and its nesting, checked before :mod:`tomllib`
(which recurses once per level of nesting) sees the text.

A file of more than :data:`MAX_CHARS` characters, or whose arrays and inline tables nest more than
:data:`MAX_NESTING` levels deep, is one :class:`UserError` line; so is invalid TOML. The nesting
is counted by a small scanner that skips strings (basic, literal, multi-line) and comments, so an
array nested 2000 deep is refused without any recursion; RecursionError and MemoryError from the
parser are caught as well, and the parsed document is at most :data:`MAX_DEPTH` levels deep
(dotted keys ``a.b.c...`` nest tables without any bracket).
"""
from __future__ import annotations

import os
import stat
import tomllib

from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.files import read_regular

MAX_CHARS = 4_000_000
MAX_NESTING = 24          # brackets of arrays and inline tables, counted in the text
MAX_DEPTH = 32            # levels of the parsed document (tables, dotted keys, arrays)


def nesting(text: str) -> int:
    """The deepest nesting of ``[``/``{`` outside strings and comments (table headers count 1-2)."""
    depth = deepest = i = 0
    n = len(text)
    while i < n:
        c = text[i]
        if c == "#":
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif c in "\"'":
            triple = text.startswith(c * 3, i)
            quote = c * 3 if triple else c
            j = i + len(quote)
            while j < n:
                if c == '"' and text[j] == "\\":
                    j += 2
                    continue
                if text.startswith(quote, j):
                    break
                if not triple and text[j] == "\n":
                    break
                j += 1
            while triple and text.startswith(c, j + 3):     # """a"""" ends with the last quotes
                j += 1
            i = j + len(quote)
            continue
        elif c in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif c in "]}":
            depth = max(depth - 1, 0)
        i += 1
    return deepest


def read_text_file(path, what: str) -> str:
    """The UTF-8 text of the input file ``path`` (``what`` names it: "experiment file"): a
    regular file (or a symlink to one) of at most 4 x :data:`MAX_CHARS` bytes, else one
    UserError line before anything is read: a FIFO would block the read for ever, /dev/zero never
    end it, a directory fail it."""
    from gnibench.suite.foundation.outputs import kind

    name = str(path)
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise UserError(f"no {what} {name!r}") from None
    except OSError as e:
        raise UserError(f"cannot read {what} {name!r} ({e.strerror})") from None
    if not stat.S_ISREG(info.st_mode):
        raise UserError(f"bad {what} {name!r}: it is {kind(info.st_mode)}; allowed: a regular "
                        f"file")
    if info.st_size > 4 * MAX_CHARS:
        raise UserError(f"{what} {name!r} is {info.st_size} bytes; allowed: a TOML file of at "
                        f"most {MAX_CHARS} characters")
    try:
        raw = read_regular(path)            # opened without blocking, checked again as read
        # a byte-order mark (some Windows editors write one) is not part of the text: TOML's
        # parser would stop at it with "Invalid statement (at line 1, column 1)"
        return raw.decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError as e:
        raise UserError(f"{what} {name!r} is not UTF-8 text (byte {e.start}); allowed: a TOML "
                        f"file in UTF-8") from None
    except OSError as e:
        raise UserError(f"cannot read {what} {name!r} ({e.strerror})") from None


def load_toml(text: str, source: str) -> dict:
    """The parsed TOML document of ``text`` (``source`` names it in errors), bounded."""
    if len(text) > MAX_CHARS:
        raise UserError(f"{source}: {len(text)} characters; allowed: a TOML file of at most "
                        f"{MAX_CHARS} characters")
    depth = nesting(text)
    if depth > MAX_NESTING:
        raise UserError(f"{source}: arrays or tables nested {depth} deep; allowed: at most "
                        f"{MAX_NESTING} levels")
    text = text.removeprefix("\ufeff")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise UserError(f"{source}: not valid TOML: {e}") from None
    except (RecursionError, MemoryError) as e:
        raise UserError(f"{source}: not valid TOML: {type(e).__name__} (nested too deep or too "
                        f"large)") from None
    depth = _depth(doc)
    if depth > MAX_DEPTH:                   # dotted keys nest tables without brackets: a.b.c...
        raise UserError(f"{source}: tables or arrays nested more than {MAX_DEPTH} deep; allowed: "
                        f"at most "
                        f"{MAX_DEPTH} levels")
    return doc


def _depth(doc) -> int:
    """The nesting depth of a parsed document, counted without recursion."""
    deepest, stack = 0, [(doc, 1)]
    while stack:
        value, depth = stack.pop()
        deepest = max(deepest, depth)
        if depth > MAX_DEPTH:
            break
        children = value.values() if isinstance(value, dict) else value
        stack.extend((v, depth + 1) for v in children if isinstance(v, (dict, list)))
    return deepest
