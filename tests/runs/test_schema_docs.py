"""The key tables of the input files are rendered from the schema records, and the
documentation's reference page shows every one of them (docs/reference/input-files.md)."""
from __future__ import annotations

import re
from pathlib import Path

import pytest
from gnibench.suite.cli import schema_docs
from gnibench.suite.foundation.records import fields
from gnibench.suite.runs.experiment_schema import Group

PAGE = Path(__file__).resolve().parents[2] / "docs" / "reference" / "input-files.md"


def test_the_reference_page_shows_every_table():
    shown = re.findall(r"^```\{gnibench-schema\} (\w+)\s*$", PAGE.read_text(encoding="utf-8"), re.M)
    assert sorted(shown) == sorted(schema_docs.TABLES), (
        f"{PAGE.name} shows the tables {shown}; the records have {sorted(schema_docs.TABLES)}")


@pytest.mark.parametrize("name", sorted(schema_docs.TABLES))
def test_every_key_of_every_record_is_in_its_table(name):
    text = schema_docs.render(name)
    for _, record, prefix in schema_docs.TABLES[name]:
        for key in fields(record):
            assert f"| `{prefix}{key}` |" in text, f"{name}: key {prefix}{key} missing"


def test_a_changed_record_changes_its_table(monkeypatch):
    before = schema_docs.render("group")
    monkeypatch.setattr(Group.model_fields["label"], "description", "a changed meaning")
    after = schema_docs.render("group")
    assert before != after and "a changed meaning" in after


def test_the_command_prints_the_tables_and_refuses_an_unknown_one(capsys):
    assert schema_docs.main(["claim"]) == 0
    assert "| `passes` |" in capsys.readouterr().out
    assert schema_docs.main(["nothing"]) == 2
    assert "unknown table 'nothing'" in capsys.readouterr().err
