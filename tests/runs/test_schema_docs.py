"""The README tables of the input files' keys are the ones rendered from the schema records."""
from __future__ import annotations

from gnibench.suite.cli import schema_docs
from gnibench.suite.runs.experiment_schema import Group


def test_readme_tables_match_the_records():
    assert schema_docs.stale() == [], (
        "the schema tables of the READMEs differ from the records; regenerate them with "
        "python -m gnibench.suite.cli.schema_docs")


def test_a_changed_record_makes_the_tables_stale(tmp_path, monkeypatch):
    for path in schema_docs.FILES:
        (tmp_path / path).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / path).write_text((schema_docs.ROOT / path).read_text())
    assert schema_docs.stale(tmp_path) == []
    monkeypatch.setattr(Group.model_fields["label"], "description", "changed")
    assert schema_docs.stale(tmp_path) == ["suite/experiments/README.md"]
    monkeypatch.undo()
    text = (tmp_path / "README.md").read_text()
    (tmp_path / "README.md").write_text(text.replace("<!-- schema: claim -->", ""))
    assert schema_docs.stale(tmp_path) == ["README.md"]
