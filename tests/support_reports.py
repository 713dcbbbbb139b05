"""A small results directory for the report tests: one run shared by the tests of a session.

Hostile texts everywhere a user or a file can put one (title, reference, description, group label,
the reason of a failing cell), a step-size sweep, a tolerance sweep and a failed cell, so pages
have every part: figures, work-precision diagrams, league tables, failed cells.
"""
from __future__ import annotations

import struct
import zlib
from pathlib import Path

HOSTILE_TITLE = "<script>alert('t')</script> # Fake | table | row"
HOSTILE_REASON = "<img src=x onerror=alert(1)> | # boom"
EXPERIMENT = '''
name = "hostile"
title = "{title}"
reference = "[HLW] <b>I.2</b> | ref"
description = """
First paragraph with <script>alert('d')</script> and **stars**.
# Fake heading in the description
| fake | table |
|---|---|
(choice) A choice with <em>markup</em> and `backticks` ```` fences.
(reading) A reading.
"""
t_end = 6.283185307179586
every = 4

[[cells]]
label = "<b>label</b> | # not a heading"
problems = ["kepler-2d"]
methods = ["rk4", "stormer-verlet"]
vary.h = [0.1, 0.05, 0.025]

[[cells]]
label = "adaptive"
problems = ["kepler-2d"]
methods = ["dopri5"]
vary.rtol = [1e-4, 1e-6, 1e-8]
vary.atol = [1e-8]
'''.replace("{title}", HOSTILE_TITLE)


def png_bytes(width: int = 40, height: int = 30) -> bytes:
    """A small valid PNG (a colour gradient), without an image library."""
    raw = b"".join(b"\x00" + b"".join(bytes((x * 6 % 256, y * 8 % 256, 120)) for x in range(width))
                   for y in range(height))

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(
            ">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw))
            + chunk(b"IEND", b""))


def make_results(root: Path, monkeypatch) -> Path:
    """Run the hostile experiment into ``root/results`` (one cell made to fail)."""
    import gnibench.suite.cell.driver
    from gnibench.suite.runs.runner import run_experiment

    real = gnibench.suite.cell.driver.integrate

    def integrate(cell, **kw):
        method = cell.method_text
        if "stormer-verlet:h=0.025" in method:
            raise RuntimeError(HOSTILE_REASON)
        return real(cell, **kw)

    monkeypatch.setattr(gnibench.suite.cell.driver, "integrate", integrate)
    path = root / "hostile.toml"
    path.write_text(EXPERIMENT, encoding="utf-8")
    out = run_experiment(path, root / "results", jobs=1, log=open("/dev/null", "w"))  # noqa: SIM115
    fig = out / "figure"
    fig.mkdir()
    (fig / "fig.png").write_bytes(png_bytes())
    (fig / "figure.json").write_text(
        '{"id": "hlw-fig-x", "number": "2.3", "caption": "Caption <script>x</script>", '
        '"reference": "[HLW] Fig 2.3", "scale": "reduced", "files": {"png": "fig.png"}, '
        '"panels": [{"title": "energy", "xlabel": "t", "ylabel": "|err H|", '
        '"curves": [{"label": "rk4 <b>"}]}], "notes": ["note | # one"]}', encoding="utf-8")
    return out


def with_method_columns(cells):
    """A hand-made cells table with the columns the runner derives from each typed cell
    (``problem_id``, ``base_method``, ``modifiers``, ``method_kind``, ``family``, ``sweep``,
    ``sweep_value``, ``adaptive``; suite/runs/tables.py), from its ``problem`` and ``method``."""
    from gnibench.suite.cell.spec import prepare

    out = cells.copy()
    specs = [prepare(str(p), str(m)) for p, m in zip(cells["problem"], cells["method"])]
    families = [m.family() for _, m in specs]
    out["problem_id"] = [p.id for p, _ in specs]
    out["base_method"] = [m.id for _, m in specs]
    out["modifiers"] = ["+".join(x.id for x in m.modifiers) for _, m in specs]
    out["method_kind"] = [m.kind for _, m in specs]
    out["family"] = [f.label for f in families]
    out["sweep"] = [f.sweep for f in families]
    out["sweep_value"] = [f.value for f in families]
    out["adaptive"] = [f.adaptive for f in families]
    return out
