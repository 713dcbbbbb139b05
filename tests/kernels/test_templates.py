"""Templates (suite/foundation/templates.py): a template's text is made once per function,
renaming and marking, and is what the renames and the mark say."""
from __future__ import annotations

from gnibench.methods.kernels import driver
from gnibench.suite.foundation.templates import template


def test_the_text_follows_each_rename_and_mark_asked():
    plain = template(driver.record_row)
    renamed = template(driver.record_row, {"record_row": "write_row", "store": "put"})
    assert plain.startswith("\n@njit(cache=True)\ndef record_row(")
    assert "def write_row(" in renamed and "put(y, out_y, row)" in renamed
    assert "record_row" not in renamed and "store(" not in renamed
    assert template(driver.record_row, {"store": "put", "record_row": "write_row"}) == renamed
    assert template(driver.record_row, inline=True).startswith(
        "\n@njit(cache=True, inline='always')\ndef record_row(")
    assert template(driver.record_row) == plain         # asked again: the same text
