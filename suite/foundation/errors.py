"""User-facing errors: one line, exit code 2, no traceback."""
from __future__ import annotations

import difflib


class UserError(Exception):
    """Bad input from the user (a spec, an option, a file). The CLI prints it on one line, exit 2."""


def unknown(kind: str, name: str, known) -> UserError:
    """Build the error for an unknown id, suggesting the nearest known one."""
    known = sorted(known)
    near = difflib.get_close_matches(name, known, n=1, cutoff=0.5)
    hint = f"; did you mean {near[0]!r}?" if near else ""
    return UserError(f"unknown {kind} {name!r}{hint} (known: {', '.join(known)})")
