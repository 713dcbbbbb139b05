"""User-facing errors: one line, exit code 2, no traceback."""
from __future__ import annotations

import contextvars
import difflib


class UserError(Exception):
    """Bad input from the user: a spec, an option, an argument, a file.

    Raised before any work is done (nothing is run or written), with one line that names the bad
    value and what is allowed. The command line prints that line (``gnibench: error: ...``) and
    exits with code 2; the Python API (``gnibench.UserError``) raises it. A diverging integration
    is not an error: it is a status of the cell.

    Examples
    --------
    >>> import gnibench
    >>> try:
    ...     gnibench.solve("kepler-2d", "rk5:h=0.01", steps=10)
    ... except gnibench.UserError as e:
    ...     print(e)                                    # doctest: +ELLIPSIS
    unknown method 'rk5'; did you mean 'rk4'? (known: ...)
    >>> try:
    ...     gnibench.solve("kepler-2d", "rk4:h=0.01", t_end="10")
    ... except gnibench.UserError as e:
    ...     print(e)
    gnibench.solve: bad t_end '10' (a str); allowed: a number, or None
    """


def edit_distance(a: str, b: str) -> int:
    """Levenshtein distance (insertions, deletions, substitutions)."""
    row = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        prev, row[0] = row[0], i
        for j, cb in enumerate(b, 1):
            prev, row[j] = row[j], min(row[j] + 1, row[j - 1] + 1, prev + (ca != cb))
    return row[-1]


def nearest(name: str, known) -> str | None:
    """The known id nearest to ``name``: case-insensitive equality first, then the fewest edits
    (at most a third of the length, ties broken by difflib's similarity)."""
    known = sorted(known)
    low = name.lower()
    for k in known:
        if k.lower() == low:
            return k
    scored = [(edit_distance(low, k.lower()), -difflib.SequenceMatcher(None, low, k.lower()).ratio(),
               k) for k in known]
    if not scored:
        return None
    dist, _, best = min(scored)
    return best if dist <= max(1, len(name) // 3) else None


def unknown(kind: str, name: str, known) -> UserError:
    """Build the error for an unknown id, suggesting the nearest known one."""
    known = sorted(known)
    near = nearest(name, known)
    hint = f"; did you mean {near!r}?" if near else ""
    return UserError(f"unknown {kind} {name!r}{hint} (known: {', '.join(known)})")


#: where the process was called from: ``"api"`` (Python, the default) or ``"cli"`` (set by the
#: command line, :func:`gnibench.suite.cli.main.main`); an error names an option as it was given
EDGE = contextvars.ContextVar("gnibench_edge", default="api")
_KEYWORDS = {"-j": "jobs", "-o": "output"}


def named(flag: str, shown: str) -> str:
    """An option and its bad value as the user gave them: ``--steps 0`` on the command line,
    ``steps=0`` from Python (the keyword of the API function; a flag ``--dt-out`` is the keyword
    ``dt_out``, ``-j`` is ``jobs``). A name that is not a flag (``steps =`` of an experiment
    file, ``GNIBENCH_MAX_STEPS=``) is kept.

    Examples
    --------
    >>> named("--dt-out", "0")
    'dt_out=0'
    >>> token = EDGE.set("cli")
    >>> named("--dt-out", "0")
    '--dt-out 0'
    >>> EDGE.reset(token)
    """
    if not flag.startswith("-"):            # GNIBENCH_MAX_STEPS=inf, steps = 0
        return f"{flag}{'' if flag.endswith('=') and not flag.endswith(' =') else ' '}{shown}"
    if EDGE.get() == "cli":
        return f"{flag} {shown}"
    return f"{spelled(flag)}={shown}"


def spelled(flag: str) -> str:
    """An option's name as the user gave it: the flag on the command line (``--dt-out``), the
    keyword from Python (``dt_out``); see :func:`named`."""
    if not flag.startswith("-") or EDGE.get() == "cli":
        return flag
    return _KEYWORDS.get(flag, flag.lstrip("-").replace("-", "_"))
