"""The documentation's generated pages cover every public id: a page per problem, method,
modifier and metric of the registries (as ``gnibench list`` lists them), every claim of the
ledger in the claims catalogue, every figure of the seeds in the gallery (docs/_ext/gnibench_docs)."""
from __future__ import annotations

import sys
import tomllib
from pathlib import Path

import pytest

import gnibench

DOCS = Path(__file__).resolve().parents[2] / "docs"
sys.path.insert(0, str(DOCS / "_ext"))

from gnibench_docs import catalogue, claims, gallery, registry  # noqa: E402


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The generated pages, written as the build writes them (the gallery without drawing)."""
    root = tmp_path_factory.mktemp("docs")
    registry.write(root)
    catalogue.write(root)
    claims.write(root)
    mp = pytest.MonkeyPatch()
    mp.setenv("GNIBENCH_DOCS_GALLERY", "skip")
    gallery.write(root, root / "_build" / "seeds")
    mp.undo()
    return root


def _listed() -> dict[str, list[str]]:
    methods = gnibench.list_methods()
    return {"problems": list(gnibench.list_problems()["id"]),
            "methods": list(methods.loc[methods["kind"] != "modifier", "id"]),
            "modifiers": list(methods.loc[methods["kind"] == "modifier", "id"]),
            "metrics": list(gnibench.list_metrics()["id"])}


@pytest.mark.parametrize("kind", registry.KINDS)
def test_every_listed_id_has_its_page(site, kind):
    ids = _listed()[kind]
    assert ids, kind
    missing = [i for i in ids if not (site / "reference" / kind / f"{i}.md").is_file()]
    assert missing == [], f"no page for the {kind} {missing}"
    index = (site / "reference" / kind / "index.md").read_text(encoding="utf-8")
    assert all(f"({i}.md)" in index for i in ids), f"the {kind} index misses some ids"
    extra = sorted(p.stem for p in (site / "reference" / kind).glob("*.md"))
    assert set(extra) - {"index"} == set(ids), "a page without an id"


def test_a_problem_page_shows_its_equations_and_options(site):
    page = (site / "reference" / "problems" / "pendulum.md").read_text(encoding="utf-8")
    assert r"\cos{\left(q \right)}" in page, "the Hamiltonian from the sympy model"
    assert "[HLW] I.1.3" in page
    page = (site / "reference" / "problems" / "kepler-2d.md").read_text(encoding="utf-8")
    assert "| `e` | `0.6` |" in page, "the option table with defaults"


def test_a_method_page_shows_its_order_properties_and_tableau(site):
    page = (site / "reference" / "methods" / "rk4.md").read_text(encoding="utf-8")
    assert "| order | 4 |" in page
    assert r"\begin{array}{c|cccc}" in page, "RK4's Butcher tableau"
    page = (site / "reference" / "methods" / "stormer-verlet.md").read_text(encoding="utf-8")
    assert "symplectic" in page and "symmetric" in page


def test_every_claim_is_in_the_catalogue(site):
    ids = []
    for path in sorted(claims.claims_dir().glob("*.toml")):
        ids += [c["id"] for c in tomllib.loads(path.read_text(encoding="utf-8")).get("claim", [])]
    text = "\n".join(p.read_text(encoding="utf-8") for p in (site / "reference" / "claims").glob("*.md"))
    missing = [i for i in ids if f"({claims.anchor(i)})=" not in text]
    assert len(ids) >= 138 and missing == []


def test_every_figure_has_a_gallery_page(site):
    from gnibench.suite.runs.experiment import shipped

    figures = [n for n, text in shipped().items() if "figure" in tomllib.loads(text)]
    assert len(figures) == 41
    pages = {p.stem for p in (site / "gallery" / "figures").glob("*.md")}
    assert set(figures) <= pages
    claimed = {c.get("figure") for cs in claims.files().values() for c in cs} - {None, ""}
    assert claimed <= set(figures), f"claims name figures that do not exist: {claimed - set(figures)}"


def test_the_catalogue_of_ids_names_every_experiment(site):
    from gnibench.suite.runs.experiment import shipped

    text = (site / "reference" / "ids.md").read_text(encoding="utf-8")
    assert all(f"`{n}`" in text for n in shipped())


def test_the_page_of_a_removed_record_goes(tmp_path):
    from gnibench_docs.common import Tree

    (tmp_path / "old-method.md").write_text("a page of a record that no longer exists")
    tree = Tree(tmp_path)
    tree.write("rk4.md", "# rk4")
    tree.prune()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rk4.md"]
