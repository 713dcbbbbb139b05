"""The command lines that the documentation shows without running them (hour-long campaigns,
benchmarks, installing a package) still parse: every ``gnibench ...`` line of the ``sh`` blocks
of the pages and the README is accepted by the command line's parser, with its options and
their values. The pages' other examples run when the documentation builds."""
from __future__ import annotations

import re
import shlex
from pathlib import Path

import pytest

from gnibench.suite.cli.main import _parser

ROOT = Path(__file__).resolve().parents[2]
GENERATED = ("reference/problems", "reference/methods", "reference/modifiers", "reference/metrics",
             "reference/claims", "gallery/figures", "_build")


def _pages() -> list[Path]:
    pages = [p for p in (ROOT / "docs").rglob("*.md")
             if not any(str(p.relative_to(ROOT / "docs")).startswith(g) for g in GENERATED)]
    return sorted(pages) + [ROOT / "README.md"]


def _commands() -> list[tuple[str, str]]:
    out = []
    for page in _pages():
        text = page.read_text(encoding="utf-8")
        for block in re.findall(r"```(?:sh|bash)\n(.*?)```", text, flags=re.DOTALL):
            for line in block.splitlines():
                line = line.split(" #", 1)[0].strip()
                if line.startswith("gnibench "):
                    out.append((str(page.relative_to(ROOT)), line))
    return out


COMMANDS = _commands()


def test_the_pages_show_commands():
    assert len(COMMANDS) >= 20


@pytest.mark.parametrize("page, command", COMMANDS, ids=[c for _, c in COMMANDS])
def test_a_shown_command_parses(page, command):
    words = shlex.split(command)[1:]
    try:
        _parser().parse_args(words)
    except SystemExit as e:                    # --help
        assert e.code == 0, f"{page}: {command}"
    except Exception as e:                     # UserError: one line naming the bad option
        pytest.fail(f"{page}: {command!r} does not parse: {e}")


def test_a_wrong_command_is_caught():
    with pytest.raises(Exception):
        _parser().parse_args(shlex.split("solve kepler-2d rk4 --t-ends 1"))
