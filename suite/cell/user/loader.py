"""Loading user definitions: files, ``GNIBENCH_LOAD``, entry points; registering their records.

* :func:`load` reads a TOML file of ``[[problem]]`` and ``[[method]]`` entries (``--load FILE``,
  an experiment's ``load = [...]``, ``gnibench.load(path)``). All its entries are built and
  checked first, then registered together; nothing is registered when one fails.
* :func:`discover` loads, once per process, the files of ``GNIBENCH_LOAD`` (paths separated by
  ``:``, empty entries skipped: :func:`load_paths`) and the entry points of the groups
  ``gnibench.problems`` and ``gnibench.methods`` (a broken entry point is a warning and is
  skipped; a bad ``GNIBENCH_LOAD`` file is an error). An entry point names a definition table (a
  dict with the keys of a file's entry; ``id`` defaults to the entry point's name), a list of
  them, or a function returning either.

Every record carries its :class:`Origin` (the file's path and text, or the entry point), so a
worker process that lacks it (a Dask worker started by spawn) defines it before resolving a
pickled reference (:mod:`gnibench.suite.foundation.registries`). A user id that collides with a
shipped id, or with one of another origin, also when they differ only in letter case, is
refused; loading the same file again is a no-op, and a changed file replaces its own earlier
definitions.
"""
from __future__ import annotations

import hashlib
import os
import time
import tomllib
from dataclasses import dataclass
from pathlib import Path

from gnibench.suite.cell.user.entries import Entry
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.foundation.guard import UserCodeError, user_code

GROUPS = {"gnibench.problems": "problem", "gnibench.methods": "method"}
ENV = "GNIBENCH_LOAD"


@dataclass(frozen=True)
class Origin:
    """Where definitions come from: ``file`` (``name`` its resolved path, ``text`` its content)
    or ``entry-point`` (``name`` = ``group:name``, ``text`` the group)."""

    kind: str
    name: str
    text: str = ""

    def load(self) -> None:
        """Define this origin's records in this process (from the text it carries)."""
        if self.kind == "file":
            _load_text(self, self.text)
        else:
            _load_entry_point(self.text, self.name[len(self.text) + 1:])

    def __str__(self) -> str:
        return self.name


#: origin name -> (digest of its text, [(kind, id)])
_LOADED: dict[str, tuple[str, list[tuple[str, str]]]] = {}
#: per loaded file, its stat and digest when its text was last found unchanged (refresh)
_CHECKED: dict[str, tuple] = {}
#: a file modified less than this long ago (ns) is read again even when its stat is unchanged:
#: two writes within one tick of the file system's clock, of the same size, have the same stat
#: (git's "racy" entries)
RACY_NS = 2_000_000_000
_discovered = False


def load(path) -> list[str]:
    """Load a definitions file; returns the ids it defines. Raises UserError naming the file,
    entry and key of a bad definition."""
    from gnibench.suite.foundation.tomlfile import read_text_file

    p = Path(path)
    text = read_text_file(p, "definitions file")
    return _load_text(Origin("file", str(p.resolve()), text), text)


def discover() -> None:
    """Load ``GNIBENCH_LOAD`` and the installed entry points, once per process."""
    global _discovered
    if _discovered:
        return
    _discovered = True                  # also while loading: a file's entries may look ids up
    try:
        for path in load_paths():
            try:
                load(path)
            except UserError as e:
                raise UserError(f"{ENV}: {e}") from None
        from importlib.metadata import entry_points

        for group in GROUPS:
            for ep in entry_points(group=group):
                _load_installed(group, ep.name)
    except BaseException:
        _discovered = False             # the next call tries again (and says so again)
        raise


def _load_installed(group: str, name: str) -> None:
    """An installed entry point, found by :func:`discover`: a broken one (it fails to import,
    raises, gives the wrong type, a bad or colliding id) is one warning line naming it and what
    is allowed, and its definitions are skipped; the shipped ones and those of the other
    packages stay usable (a broken plugin made every solve, list and run exit with code 2)."""
    from gnibench.suite.foundation.cache import warn

    try:
        _load_entry_point(group, name)
    except UserError as e:
        warn(f"{e}; its definitions are skipped (fix or uninstall its package)")


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def load_paths() -> list[str]:
    """The files named by ``GNIBENCH_LOAD``: entries separated by ``:`` (``;`` on
    Windows), blanks around an entry ignored. Empty entries (``::``, a leading or trailing
    ``:``) are skipped, so that ``GNIBENCH_LOAD="$GNIBENCH_LOAD:defs.toml"`` works whether it was
    set or not (unlike PATH, where an empty entry is the current directory); every other entry
    must be a definitions file (a missing one is an error, not skipped)."""
    return [p.strip() for p in os.environ.get(ENV, "").split(os.pathsep) if p.strip()]


def loaded() -> dict[str, list[tuple[str, str]]]:
    """The origins loaded in this process and the (kind, id) each defined."""
    return {name: list(ids) for name, (_, ids) in _LOADED.items()}


def unload(name: str | Path | None = None) -> None:
    """Remove the records of one origin (a file path or ``group:name``), or of all."""
    from gnibench.methods import METHODS
    from gnibench.problems import REGISTRY

    names = list(_LOADED) if name is None else [str(Path(name).resolve()) if Path(
        name).exists() else str(name)]
    for n in names:
        _, ids = _LOADED.pop(n, ("", []))
        for kind, rid in ids:
            (REGISTRY if kind == "problem" else METHODS).pop(rid, None)


def refresh() -> None:
    """Load again every definitions file loaded in this process whose text on disk, or whose
    Python integrators' module source, has changed since (the API calls this before each
    ``solve`` and ``run``: a notebook sees its edited definitions, as a new command would)."""
    for name in [n for n, (digest, _) in _LOADED.items() if digest]:
        try:
            st = os.stat(name)
        except OSError:
            continue                                 # gone: keep what was loaded
        seen = (st.st_mtime_ns, st.st_ctime_ns, st.st_size, st.st_ino, _LOADED[name][0])
        if _CHECKED.get(name) != seen:               # the file may have changed: read it
            try:
                text = Path(name).read_text(encoding="utf-8")
            except (OSError, UnicodeDecodeError):
                continue                             # unreadable: keep what was loaded
            if hashlib.sha256(text.encode()).hexdigest() != _LOADED[name][0]:
                load(name)
                continue
            if time.time_ns() - st.st_mtime_ns > RACY_NS:   # an older stat can be trusted
                _CHECKED[name] = seen
        if _stale(name):
            load(name)


def _stale(name: str) -> bool:
    """Whether a Python integrator of the origin ``name`` was built from a module source that
    has changed since."""
    import json

    from gnibench.methods import METHODS
    from gnibench.suite.cell.user.python_methods import entry_code

    for kind, rid in _LOADED.get(name, ("", []))[1]:
        record = METHODS.get(rid) if kind == "method" else None
        if record is None or getattr(record, "kind", "") != "python":
            continue
        code = json.loads(record.definition or "{}").get("code")
        base = str(Path(name).parent)
        try:
            if entry_code(record.entry, base)[1] != code:
                return True
        except Exception:  # noqa: BLE001 - the module is broken now: build again, and say so
            return True
    return False


def _load_text(origin: Origin, text: str) -> list[str]:
    digest = hashlib.sha256(text.encode()).hexdigest()
    if origin.name in _LOADED:
        if _LOADED[origin.name][0] == digest and not _stale(origin.name):
            return [rid for _, rid in _LOADED[origin.name][1]]
        unload(origin.name)                          # the file changed: its new definitions
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise UserError(f"{origin.name}: not valid TOML: {e}") from None
    bad = [k for k in doc if k not in ("problem", "method")]
    if bad:
        raise UserError(f"{origin.name}: unknown key {bad[0]!r}; allowed: [[problem]] and "
                        f"[[method]] entries")
    tables = []
    for kind in ("problem", "method"):
        entries = doc.get(kind, [])
        if not isinstance(entries, list) or not all(isinstance(t, dict) for t in entries):
            raise UserError(f"{origin.name}: {kind} must be an array of tables ([[{kind}]])")
        tables += [Entry(origin.name, kind, k, t) for k, t in enumerate(entries, 1)]
    return _register(origin, digest, tables)


def _load_entry_point(group: str, name: str) -> list[str]:
    from importlib.metadata import entry_points

    origin = Origin("entry-point", f"{group}:{name}", group)
    if origin.name in _LOADED:
        return [rid for _, rid in _LOADED[origin.name][1]]
    found = [ep for ep in entry_points(group=group) if ep.name == name]
    if not found:
        raise UserError(f"no entry point {name!r} in the group {group}")
    try:
        with user_code(f"entry point {origin.name} ({found[0].value})"):
            obj = found[0].load()
            obj = obj() if callable(obj) else obj
    except UserCodeError as e:          # a broken plugin (sys.exit included): one line naming it
        raise UserError(f"{str(e).replace(': ', ' cannot be loaded: ', 1)}") from None
    items = obj if isinstance(obj, list) else [obj]
    allowed = "a definition table (dict), a list of them, or a function returning either"
    if not isinstance(obj, (list, dict)):
        raise UserError(f"entry point {origin.name} gives {type(obj).__name__}; allowed: {allowed}")
    for k, t in enumerate(items):
        if not isinstance(t, dict):
            raise UserError(f"entry point {origin.name} gives a list whose element {k} is "
                            f"{type(t).__name__} ({_short(t)}); allowed: {allowed}")
    kind = GROUPS[group]
    tables = [Entry(f"entry point {origin.name}", kind, k, {"id": name, **t})
              for k, t in enumerate(items, 1)]
    return _register(origin, "", tables)


def _register(origin: Origin, digest: str, tables: list[Entry]) -> list[str]:
    """Build every entry, check the ids, then register them all."""
    from gnibench.methods import ALIASES, METHODS, MODIFIERS
    from gnibench.problems import INTERNAL, REGISTRY
    from gnibench.suite.cell.user.methods import build_method
    from gnibench.suite.cell.user.problems import build_problem

    built: dict[tuple[str, str], object] = {}

    def known(mid: str):
        return built.get(("method", mid)) or METHODS.get(ALIASES.get(mid, mid))

    for e in tables:
        rid = e.ident()
        taken = {"problem": (REGISTRY, INTERNAL), "method": (METHODS, ALIASES, MODIFIERS)}[e.kind]
        mine = [b for k, b in built if k == e.kind]
        names = [i for r in (*taken, mine) for i in r]
        clash = rid if rid in names else next(      # or one in another letter case: RK4, rk4
            (i for i in names if i.casefold() == rid.casefold()), None)
        if clash is not None:
            owner = next((r for r in taken if clash in r), None)
            record = owner.get(clash) if isinstance(owner, dict) else None
            where = getattr(record, "origin", None)
            what = f"the one of {where}" if where is not None else "a shipped one"
            if clash in mine:
                what = "another entry of this file"
            if clash != rid:
                what = f"{clash!r}, {what}, in all but letter case"
            raise e.error("id", f"{e.kind} id {rid!r} collides with {what}; allowed: an id that "
                                f"is not taken, in any letter case (gnibench list {e.kind}s)")
        record = build_problem(e, origin) if e.kind == "problem" else build_method(e, origin, known)
        built[(e.kind, rid)] = record
    for (kind, rid), record in built.items():
        (REGISTRY if kind == "problem" else METHODS)[rid] = record
    _LOADED[origin.name] = (digest, list(built))
    return [rid for _, rid in built]
