"""One entry of a definitions file (a ``[[problem]]`` or ``[[method]]`` table) and its errors.

Every error names the file (or entry point), the entry (its kind, position and id) and the key:
``defs.toml: [[method]] 2 (id 'my-rk'), key 'order': ...``.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

from gnibench.suite.cell.user.expressions import ExpressionError, number, parse
from gnibench.suite.foundation.errors import UserError

ID = re.compile(r"^[A-Za-z][A-Za-z0-9_-]*$")
#: the longest id a definition may have (an id names cache files: a file name has at most 255
#: bytes, and the cache adds a digest and a suffix to it)
MAX_ID = 64
NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


@dataclass
class Entry:
    """A definition table with where it comes from."""

    source: str            # the file's path, or the entry point
    kind: str              # "problem" | "method"
    index: int             # 1-based position among the entries of its kind
    table: dict

    @property
    def id(self) -> str:
        value = self.table.get("id")
        return value if isinstance(value, str) else "?"

    def where(self, key: str | None = None) -> str:
        rid = self.id if len(self.id) <= MAX_ID else self.id[:20] + "..."
        at = f"{self.source}: [[{self.kind}]] {self.index} (id {rid!r})"
        return at + (f", key {key!r}" if key else "")

    def error(self, key: str | None, message: str) -> UserError:
        return UserError(f"{self.where(key)}: {message}")

    def keys(self, allowed: tuple[str, ...]) -> None:
        for key in self.table:
            if key not in allowed:
                raise self.error(key, f"unknown key; allowed: {', '.join(allowed)}")

    def text(self, key: str, default: str | None = None, one_line: bool = True) -> str:
        value = self.table.get(key, default)
        if value is None:
            raise self.error(key, "missing (a string)")
        if not isinstance(value, str) or (one_line and any(not c.isprintable() for c in value)):
            raise self.error(key, f"bad value {value!r}; allowed: a string on one line")
        return value

    def ident(self) -> str:
        value = self.table.get("id")
        if not isinstance(value, str) or not ID.match(value) or len(value) > MAX_ID:
            shown = repr(value) if not isinstance(value, str) or len(value) <= 40 else \
                f"{value[:20]!r}... ({len(value)} characters)"
            raise self.error("id", f"bad id {shown}; allowed: a letter, then letters, digits, "
                                   f"- and _, at most {MAX_ID} characters")
        return value

    def names(self, key: str, required: bool = True) -> list[str]:
        value = self.table.get(key)
        if value is None and not required:
            return []
        if not isinstance(value, list) or not value or not all(
                isinstance(v, str) and NAME.match(v) for v in value) or len(set(value)) != len(value):
            raise self.error(key, f"bad value {value!r}; allowed: a list of distinct names "
                                  f"(letters, digits, _)")
        return value

    def table_of(self, key: str, required: bool = False) -> dict:
        value = self.table.get(key)
        if value is None and not required:
            return {}
        if not isinstance(value, dict) or not value:
            raise self.error(key, f"bad value {value!r}; allowed: a table of name = value")
        for name in value:
            if not NAME.match(name):
                raise self.error(key, f"bad name {name!r}; allowed: letters, digits, _")
        return value

    def expr(self, key: str, text, names: dict):
        """A sympy expression of the entry's text at ``key`` (a sub-key after a dot)."""
        try:
            return parse(text, names)
        except ExpressionError as e:
            raise self.error(key, str(e)) from None

    def constant(self, key: str, text, names: dict | None = None):
        try:
            return number(text, names)
        except ExpressionError as e:
            raise self.error(key, str(e)) from None

    def flag(self, key: str, default: bool = False) -> bool:
        value = self.table.get(key, default)
        if not isinstance(value, bool):
            raise self.error(key, f"bad value {value!r}; allowed: true or false")
        return value

    def integer(self, key: str, low: int, high: int, required: bool = True) -> int | None:
        value = self.table.get(key)
        if value is None and not required:
            return None
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
            raise self.error(key, f"bad value {value!r}; allowed: an integer from {low} to {high}")
        return value
