"""Reading results directories back: the tables and metadata a report is drawn from.

A results directory is what ``gnibench run`` writes (``cells.parquet``, ``samples.parquet``,
``timings.parquet``), or a directory holding several of those one level down (``gnibench verify``
writes one per experiment, next to ``ledger.parquet``). A results directory may also hold
``figure/figure.json``, the manifest of a reproduced figure ([`gnibench reproduce`]): its images,
caption and notes go on the experiment's page. Only tables and files are read; nothing is
integrated.
"""
from __future__ import annotations

import contextlib
import json
import re
from dataclasses import dataclass, field
from pathlib import Path

from gnibench.suite.foundation.errors import UserError

IMAGE_SUFFIXES = (".png", ".svg")


@dataclass
class Results:
    """One experiment's results: its directory, provenance, cells (with family columns) and
    timings; samples are read on demand (they can be large)."""

    dir: Path
    meta: dict
    cells: object
    timings: object
    written_at: str = ""
    figure: dict | None = None
    figure_error: str = ""

    @property
    def name(self) -> str:
        return str(self.meta.get("experiment") or self.dir.name)

    def samples(self, columns: list[str] | None = None):
        import pyarrow.parquet as pq

        path = self.dir / "samples.parquet"
        with damaged(path):
            have = set(pq.read_schema(path).names)
        cols = None if columns is None else [c for c in columns if c in have]
        return read_table(path, cols)

    def wall_by_cell(self) -> dict[int, float]:
        """Each cell's wall time (s): the fastest of its repeated timed runs."""
        t = self.timings
        return {int(c): float(w) for c, w in zip(t["cell"], t["wall_seconds"])} if len(t) else {}

    def wall_stats(self) -> dict[int, tuple[float, float, float, int]]:
        """Each cell's wall times: :func:`timing_stats` of the timings table."""
        return timing_stats(self.timings)


def timing_stats(t) -> dict[int, tuple[float, float, float, int]]:
    """Each cell's wall times (s) from a timings table: (fastest, median, spread (max - min) /
    median, runs); tables written before repeated timings count one run."""
    if t is None or not len(t):
        return {}
    w = t["wall_seconds"].to_numpy(float)
    med = t["wall_median_seconds"].to_numpy(float) if "wall_median_seconds" in t else w
    spread = t["wall_spread"].to_numpy(float) if "wall_spread" in t else 0 * w
    runs = t["repeats"].to_numpy(int) if "repeats" in t else (w == w).astype(int)
    return {int(c): (float(a), float(b), float(s), int(n))
            for c, a, b, s, n in zip(t["cell"], w, med, spread, runs)}


@dataclass
class Ledger:
    """A claims ledger (``ledger.parquet`` of ``gnibench verify``), shown as a table."""

    dir: Path
    table: object
    meta: dict = field(default_factory=dict)


@contextlib.contextmanager
def damaged(path: Path):
    """A table that cannot be read (truncated, damaged, not Parquet) is a one-line UserError."""
    try:
        yield
    except Exception as e:  # noqa: BLE001 - pyarrow raises many kinds; all mean the same here
        why = " ".join(str(e).split())[:160] or type(e).__name__
        raise UserError(f"cannot read {path} ({why}); it is damaged or not a gnibench table: "
                        f"run the command that wrote it again") from None


def read_table(path: Path, columns: list[str] | None = None):
    import pandas as pd
    from gnibench.suite.foundation.files import open_regular_file

    with damaged(path), open_regular_file(path) as f:
        return pd.read_parquet(f, columns=columns)


def parquet_meta(path: Path) -> dict:
    """The provenance (schema metadata key ``gnibench``) of a Parquet file."""
    import pyarrow.parquet as pq
    from gnibench.suite.foundation.files import open_regular_file

    with damaged(path), open_regular_file(path) as f:
        md = pq.read_schema(f).metadata or {}
        return json.loads(md.get(b"gnibench", b"{}"))


def is_results_dir(path: Path) -> bool:
    return all((path / f).is_file() for f in ("cells.parquet", "samples.parquet", "timings.parquet"))


#: what a report reads of cells.parquet: the specs and what the runner derived from the typed
#: cell (its problem id, base method, modifiers, how the method runs, its family), so that no
#: spec text is parsed again here
CELL_COLUMNS = ("cell", "problem", "method", "status", "h", "t_end", "problem_id", "base_method",
                "modifiers", "method_kind", "family", "sweep", "sweep_value", "adaptive")
#: columns that tables written before gnibench 0.2 lack
NEWER = ("problem_id", "base_method", "modifiers", "family", "sweep", "sweep_value", "adaptive")


def _ours(table, path: Path, columns):
    """``table`` when it has the columns a gnibench table has, else a one-line UserError (a
    Parquet file of another program under the same name was a KeyError traceback)."""
    missing = [c for c in columns if c not in table.columns]
    if missing and all(c in NEWER for c in missing):
        raise UserError(f"cannot read {path} (no column {missing[0]!r}): it was written by an "
                        f"earlier gnibench; run the command that wrote it again")
    if missing:
        raise UserError(f"cannot read {path} (no column {missing[0]!r}); it is damaged or not a "
                        f"gnibench table: run the command that wrote it again")
    return table


def load_results(path: Path) -> Results:
    """Read one results directory (see the module docstring)."""

    from gnibench.suite.runs.storage import check_table_set

    path = Path(path)
    check_table_set(path)
    meta = parquet_meta(path / "cells.parquet")
    cells = _ours(read_table(path / "cells.parquet"), path / "cells.parquet", CELL_COLUMNS)
    timings = _ours(read_table(path / "timings.parquet"), path / "timings.parquet",
                    ("cell", "wall_seconds", "compile_seconds"))
    written = str(parquet_meta(path / "timings.parquet").get("written_at", ""))
    res = Results(path, meta, cells, timings, written)
    if (path / "figure" / "figure.json").exists():
        try:
            res.figure = load_manifest(path / "figure")
        except (ValueError, TypeError, OSError) as e:
            res.figure_error = f"figure/figure.json could not be used: {e}"
    return res


def find_results(dirs: list[Path]) -> tuple[list[Results], list[Ledger]]:
    """Every results directory given, or one level below a given directory; ledgers beside them.
    A directory with neither is a one-line UserError."""

    found: list[Results] = []
    ledgers: list[Ledger] = []
    for d in dirs:
        d = Path(d)
        if not d.is_dir():
            raise UserError(f"no results directory {str(d)!r}")
        inner = [d] if is_results_dir(d) else sorted(p for p in d.iterdir()
                                                       if p.is_dir() and is_results_dir(p))
        if (d / "ledger.parquet").is_file():
            ledgers.append(Ledger(d, read_table(d / "ledger.parquet"),
                                  parquet_meta(d / "ledger.parquet")))
        if not inner and not (d / "ledger.parquet").is_file():
            raise UserError(f"{d} holds no results (cells.parquet, samples.parquet, "
                            "timings.parquet), here or one level down; allowed: the output "
                            "directory of gnibench run or verify")
        found += [load_results(p) for p in inner]
    return found, ledgers


def _strings(value, what: str) -> list[str]:
    if value is None:
        return []
    if isinstance(value, str):
        return [value]
    if isinstance(value, list) and all(isinstance(v, str) for v in value):
        return value
    raise TypeError(f"{what} must be a string or a list of strings")


def load_manifest(figure_dir: Path) -> dict:
    """A reproduced figure's manifest, checked: its image files must be PNG or SVG files inside
    ``figure_dir`` (no absolute paths, no ``..``). Returns a plain dict of strings and lists:
    id, number, caption, reference, scale, notes, images (relative paths), panels (title, x and
    y labels, curve labels)."""
    doc = json.loads((figure_dir / "figure.json").read_text(encoding="utf-8"))
    if not isinstance(doc, dict):
        raise TypeError("the manifest is not a JSON object")
    files = doc.get("files", [])
    if isinstance(files, dict):
        files = list(files.values())
    files = _strings(files, "files")
    root = figure_dir.resolve()
    images = []
    for f in files:
        target = (figure_dir / f).resolve()
        if Path(f).is_absolute() or not target.is_relative_to(root):
            raise ValueError(f"file {f!r} lies outside figure/")
        if target.suffix.lower() == ".md":
            continue                    # a table figure's table.md: not an image
        if target.suffix.lower() not in IMAGE_SUFFIXES:
            raise ValueError(f"file {f!r} is not a PNG or SVG image (or a table's .md)")
        if not target.is_file():
            raise ValueError(f"file {f!r} does not exist")
        images.append(target.relative_to(root).as_posix())
    if any(i.lower().endswith(".png") for i in images):   # the PNG is shown; its SVG twin is not
        images = [i for i in images if i.lower().endswith(".png")]
    panels = []
    for p in doc.get("panels", []) or []:
        if not isinstance(p, dict):
            raise TypeError("a panel must be an object")
        curves = [c.get("label", "") if isinstance(c, dict) else str(c) for c in p.get("curves", [])]
        # the pages do not render mathtext: its labels as plain Unicode there; the pages list the
        # labelled curves (an unlabelled one, such as the eyes of [HLW] Fig 1.1's cat, left ", ,")
        panels.append({k: plain_math(str(p.get(k, "") or "")) for k in ("id", "title", "xlabel",
                                                                          "ylabel")}
                      | {"curves": [plain_math(str(c)) for c in curves if str(c).strip()]})
    text = {k: "" if doc.get(k) is None else str(doc.get(k))
            for k in ("id", "number", "caption", "reference", "scale")}
    notes = _strings(doc.get("notes"), "notes") + _strings(doc.get("note") or None, "note")
    return {**text, "notes": notes, "images": images,
            "panels": panels}


_SLUG = re.compile(r"[^A-Za-z0-9._-]+")


def slug(text: str) -> str:
    """A file-name-safe form of a name (letters, digits, . _ -)."""
    s = _SLUG.sub("_", str(text)).strip("._") or "x"
    return s[:60]


#: mathtext commands of the seeds' labels, as Unicode
_SYMBOLS = {"mu": "μ", "varphi": "φ", "phi": "ϕ", "Phi": "Φ", "theta": "θ", "alpha": "α",
            "beta": "β", "gamma": "γ", "omega": "ω", "Omega": "Ω", "lambda": "λ", "sigma": "σ",
            "tau": "τ", "epsilon": "ε", "pi": "π", "Delta": "Δ", "delta": "δ", "times": "×"}
_SCRIPTS = {"^": str.maketrans("0123456789-+n", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻⁺ⁿ"),
            "_": str.maketrans("0123456789-+nthkie", "₀₁₂₃₄₅₆₇₈₉₋₊ₙₜₕₖᵢₑ")}
_INLINE_MATH = re.compile(r"\$([^$]*)\$")


def plain_math(text: str) -> str:
    """A label with mathtext (``fit $t^{0.24}$``, ``$\\Phi_h^2(A)$``) as plain Unicode for the
    HTML and Markdown pages, which do not render TeX: symbols as letters (Φ), a super- or
    subscript as its Unicode character where every one of its characters has one (Φₕ²),
    else written ``^0.24``; the dollars and braces dropped. Text without ``$`` is unchanged."""
    def script(m: re.Match) -> str:
        mark, body = (m.group(1), m.group(2)) if m.group(1) else (m.group(3), m.group(4))
        table = _SCRIPTS[mark]
        return body.translate(table) if all(c in table for c in map(ord, body)) else mark + body

    def plain(m: re.Match) -> str:
        s = re.sub(r"\\mathdefault\{([^{}]*)\}", r"\1", m.group(1))
        s = s.replace("\\,", "\u2009").replace("\\ ", " ")
        s = re.sub(r"\\([A-Za-z]+)", lambda g: _SYMBOLS.get(g.group(1), g.group(1)), s)
        s = re.sub(r"([\^_])\{([^{}]*)\}|([\^_])(.)", script, s)
        return s.replace("{", "").replace("}", "")

    return _INLINE_MATH.sub(plain, text)
