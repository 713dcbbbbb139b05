"""The catalogue of the claims ledger, generated from ``suite/claims/*.toml``.

One page per file (a section of a seed), one entry per claim: where the seed says it, the claim
in our words, what the seed says, how it is checked (the pass and partly criteria over the named
values), whose threshold it is, the outcome recorded as expected, and the figure it belongs to.
The verdicts of a run are on the gallery pages and in ``gnibench verify``'s ledger, not here:
this is what is claimed and how it is judged.
"""
from __future__ import annotations

import tomllib
from pathlib import Path

from .common import Tree, cell, code, table

TITLES = {"b-2": "[B] §2: the observer and the penalty", "b-3": "[B] §3: the Main Lemma",
          "b-4.1": "[B] §4.1: the radial Kepler problem", "b-4.2": "[B] §4.2: the double oscillator",
          "b-5": "[B] §5: the spatial Kepler problem", "b-6": "[B] §6: Gavrilov–Shil'nikov",
          "b-7": "[B] §7: Euler's equations on so(4)", "b-8": "[B] §8: the geodesic flow of genus 2",
          "b-x": "[B] across sections", "hlw-1": "[HLW] I.1: first problems and methods",
          "hlw-2": "[HLW] I.2: the Kepler problem and the outer solar system",
          "hlw-3": "[HLW] I.3: the Hénon–Heiles model", "hlw-table-2.1": "[HLW] Table 2.1"}


def claims_dir() -> Path:
    import gnibench

    return Path(gnibench.__file__).resolve().parent / "suite" / "claims"


def files() -> dict[str, list[dict]]:
    """{file stem: [claim tables]} of the ledger, in file order."""
    out = {}
    for path in sorted(claims_dir().glob("*.toml")):
        out[path.stem] = tomllib.loads(path.read_text(encoding="utf-8")).get("claim", [])
    return out


def anchor(claim_id: str) -> str:
    """The label of a claim's entry (``{ref}`claim-b-4.2-d```)."""
    return "claim-" + claim_id.lower()


def _entry(c: dict) -> str:
    out = [f"({anchor(c['id'])})=", f"### {c['id']}\n", f"*{c.get('citation', '')}*\n",
           " ".join(str(c.get("claim", "")).split()) + "\n"]
    rows = []
    if c.get("seed_value"):
        rows.append(["the seed says", cell(c["seed_value"])])
    kind = {"E": "a measurement (needs a run)", "I": "an identity or a structure"}.get(c.get("kind"))
    if kind:
        rows.append(["kind", kind])
    if c.get("experiment"):
        rows.append(["runs of", code(c["experiment"])])
    if c.get("values"):
        rows.append(["values", cell("; ".join(f"{k} = {_value(v)}" for k, v in c["values"].items()))])
    for key, label in (("closed_form", "closed form"), ("check", "identity"),
                       ("measured", "measured"), ("passes", "reproduced when"),
                       ("partly", "partly when")):
        if c.get(key):
            rows.append([label, code(c[key])])
    if c.get("all_of"):
        rows.append(["reproduced when all of", cell(", ".join(c["all_of"]))])
    if c.get("sweep"):
        rows.append(["judged once per", code(c["sweep"])])
    rows.append(["threshold", cell(c.get("threshold", "proposed"))])
    rows.append(["expected outcome", cell(c.get("expected", "reproduced"))])
    if c.get("accept"):
        rows.append(["failures that are the claim", cell(", ".join(c["accept"]))])
    if c.get("scale"):
        rows.append(["scale", cell(f"{c['scale']} only (skipped at the quick scale)")])
    if c.get("figure"):
        rows.append(["figure", f"{{doc}}`{c['figure']} </gallery/figures/{c['figure']}>`"])
    out.append(table(["", "this claim"], rows))
    for key, label in (("reading", "Reading"), ("not_checkable", "Not checkable"),
                       ("note", "Note"), ("needed", "What would be needed")):
        if c.get(key):
            out.append(f"**{label}.** " + " ".join(str(c[key]).split()) + "\n")
    return "\n".join(out)


def _value(v) -> str:
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k}: {x}" for k, x in v.items()) + "}"
    return str(v)


def section_page(stem: str, claims: list[dict]) -> str:
    title = TITLES.get(stem, stem)
    out = [f"# Claims of {title}\n", f"{len(claims)} entries of `suite/claims/{stem}.toml`.\n"]
    out += [_entry(c) for c in claims]
    return "\n".join(out)


def index_page(by_file: dict[str, list[dict]]) -> str:
    n = sum(len(v) for v in by_file.values())
    rows = []
    for stem, claims in by_file.items():
        for c in claims:
            rows.append([f"{{ref}}`{c['id']} <{anchor(c['id'])}>`", cell(c.get("citation", "")),
                         cell(c.get("expected", "reproduced")), cell(c.get("threshold", "proposed")),
                         cell(c.get("figure", ""))])
    pages = "\n".join(f"{stem}" for stem in by_file)
    return (
        "# The claims\n\n"
        f"The claims ledger holds {n} entries, one per checkable claim of the seeds [B] and [HLW] "
        "(and a second entry `<id>.corrected` beside a claim the seed prints with a slip). Each "
        "page below is one file of `suite/claims/`; `gnibench verify` judges them "
        "({doc}`/explanation/ledger` explains how, the {doc}`gallery </gallery/index>` shows the "
        "verdicts of this build).\n\n"
        + table(["claim", "where", "expected", "threshold", "figure"], rows)
        + f"\n```{{toctree}}\n:hidden:\n\n{pages}\n```\n")


def write(srcdir: Path) -> None:
    by_file = files()
    tree = Tree(srcdir / "reference" / "claims")
    tree.write("index.md", index_page(by_file))
    for stem, claims in by_file.items():
        tree.write(f"{stem}.md", section_page(stem, claims))
    tree.prune()


def by_figure() -> dict[str, list[dict]]:
    """{figure id: [claims]} of the ledger."""
    out: dict[str, list[dict]] = {}
    for claims in files().values():
        for c in claims:
            if c.get("figure"):
                out.setdefault(c["figure"], []).append(c)
    return out
