"""Input files against their schemas (suite/runs/experiment_schema.py, figure_schema.py,
suite/ledger/entries.py): every attack on a size, a number, a format or a nesting gives one line
and exit code 2 before any work, and writes nothing; errors name the file and the key's path."""
from __future__ import annotations

import pytest
from gnibench.suite.cli.main import main
from gnibench.suite.foundation.errors import UserError
from gnibench.suite.ledger.entries import parse_claims
from gnibench.suite.runs.experiment import parse_experiment

HEAD = 'name = "a"\ntitle = "t"\nreference = "r"\nt_end = 1.0\n'
CELLS = '[[cells]]\nproblems = ["pendulum"]\nmethods = ["euler:h=0.1"]\n'
PANEL = '[[figure.panels]]\ny = "p"\n[[figure.panels.curves]]\ncells = { group = 0 }\n'


def figure(extra: str) -> str:
    return HEAD + CELLS + '[figure]\nnumber = "Fig 1"\ncaption = "c"\n' + extra


def field(fixed: str) -> str:
    return figure('[[figure.panels]]\n[[figure.panels.fields]]\nproblem = "henon-heiles"\n'
                  'function = "H"\nx = "q2"\ny = "p2"\n'
                  f'fixed = {{ q1 = {fixed} }}\nxrange = [-1, 1]\nyrange = [-1, 1]\n'
                  'levels = [0.1]\n')


ATTACKS = {
    "array nested 2000 deep": (HEAD + "x = " + "[" * 2000 + "]" * 2000 + "\n" + CELLS,
                               "nested 2000 deep"),
    "dotted keys 3000 deep": (HEAD + CELLS + "vary.h" + ".a" * 3000 + " = [1]\n",
                              "nested more than 32 deep"),
    "fixed: 400 hex digits in an expression": (field('"0x' + "f" * 400 + '"'),
                                               "fields[0]: fixed.q1: bad expression"),
    "fixed: 400 hex digits as a number": (field("0x" + "f" * 400),
                                          "fixed.q1: bad value <an integer of 1600 bits>"),
    "fixed: 100000 unary minus": (field('"' + "-" * 100000 + '1"'), "100001 characters"),
    "fixed: 1e400": (field('"1e400"'), "not finite"),
    "fixed: 1/0": (field('"1/0"'), "1 / 0 is not a finite number"),
    "fixed: overflow": (field('"2.0 ** 5000"'), "is not a finite number"),
    "fixed: a call": (field('"__import__(\'os\')"'), "calls a function; none is allowed here"),
    "fixed: an attribute": (field('"p2.real"'), "uses Attribute"),
    "fixed: an unknown name": (field('"q1 + 1"'), "unknown name 'q1'"),
    "label width 5e9": (figure(PANEL + 'label = "{=h:5000000000}"\n'), "bad format '5000000000'"),
    "label width 2e8": (figure(PANEL + 'label = "{=h:200000000.1f}"\n'), "bad format"),
    "label precision 1e6": (figure(PANEL + 'label = "{=h:.1000000f}"\n'), "bad format"),
    "layout 100000 x 100000": (figure("layout = [100000, 100000]\n" + PANEL),
                               "figure: bad layout[0] = 100000"),
    "size 1e6 x 1e6": (figure("size = [1e6, 1e6]\n" + PANEL), "figure: bad size[0] = 1000000.0"),
    "grid n": (field("0.0").replace("levels", "n = 100000\nlevels"), "bad n = 100000"),
    "linewidth": (figure(PANEL + "linewidth = 1e300\n"), "bad linewidth = 1e+300"),
    "300 digits of every": (HEAD + CELLS + "every = " + "9" * 300 + "\n",
                            "bad every = <an integer of 997 bits>"),
    "steps inf": (HEAD.replace("t_end = 1.0", "t_end = inf") + CELLS, "bad t_end = inf"),
    "vary value": (HEAD + CELLS + 'vary.h = [0.1, "a b"]\n', "cells[0]: vary.h: bad value 'a b'"),
    "points n": (HEAD + CELLS + '[cells.points]\noptions = ["q0", "p0"]\n'
                 'circle = { center = [0, 1], radius = 0.1, n = 100000000 }\n',
                 "cells[0].points.circle: bad n = 100000000"),
    "a title with a line break": (HEAD.replace('"t"', '"t\\nu"') + CELLS, "bad title = 't\\nu'"),
    "unknown key": (HEAD + CELLS + "metods = 1\n", "cells[0]: unknown key 'metods'; did you mean"),
    "unknown figure key": (figure("colour = 1\n" + PANEL), "figure: unknown key 'colour'"),
    "a 5 MB file": (HEAD + CELLS + "#" * 5_000_000 + "\n", "characters; allowed: a TOML file"),
}


@pytest.mark.parametrize("case", sorted(ATTACKS))
def test_attack_is_one_line_exit_2_and_writes_nothing(case, tmp_path, capsys):
    text, message = ATTACKS[case]
    path = tmp_path / "bad.toml"
    path.write_text(text, encoding="utf-8")
    out = tmp_path / "out"
    assert main(["run", str(path), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and message in err, err[:500]
    assert err.startswith("gnibench: error: bad.toml") and len(err) < 1000
    assert not out.exists()


@pytest.mark.parametrize("scale", ["paper", "quick"])
def test_bad_override_of_the_other_scale_is_found_whichever_runs(scale):
    text = HEAD + "[scale.quick]\nevery = 0\n" + CELLS
    with pytest.raises(UserError, match=r"x.toml: scale.quick: bad every = 0; allowed: an "
                                        r"integer from 1 to 2\^62"):
        parse_experiment(text, "x.toml", scale)


def test_errors_name_the_path_of_the_key():
    cases = {
        CELLS + "[[cells]]\nproblems = []\nmethods = [\"rk4\"]\n":
            "x.toml: cells[1]: bad problems = []; allowed: a non-empty list of spec strings",
        CELLS + "steps = 5\nt_end = 2.0\n": "x.toml: cells[0]: both steps and t_end given",
        CELLS + "label = 3\n": "x.toml: cells[0]: bad label = 3; allowed: one line of text",
        CELLS + "[cells.scale.fast]\nsteps = 3\n": "cells[0].scale: unknown key 'fast'",
    }
    for body, message in cases.items():
        with pytest.raises(UserError) as e:
            parse_experiment(HEAD + body, "x.toml")
        assert message in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(UserError, match=r"x.toml: figure.panels\[0\].curves\[0\]: bad style = "
                                        r"'lines'; allowed: line \| dots"):
        parse_experiment(figure(PANEL + 'style = "lines"\n'), "x.toml")


CLAIM = 'id = "B-9-a"\nkind = "I"\ncitation = "c"\nclaim = "x"\ncheck = "arithmetic"\n'


@pytest.mark.parametrize("passes, message", [
    ('"1/0 > 1"', "1 / 0 is not a finite number"), ('"x > 1e400"', "not finite"),
    ('"' + "-" * 100000 + '1 > 0"', "bad passes"), ('"x > 0x' + "f" * 400 + '"', "bits"),
    ('"x.real > 0"', "uses Attribute"), ('"open(x) > 0"', "calls only"),
])
def test_claim_expressions_are_bounded(passes, message):
    with pytest.raises(UserError, match=message) as e:
        parse_claims(f"[[claim]]\n{CLAIM}passes = {passes}\n", "x.toml")
    assert str(e.value).startswith("x.toml: claim B-9-a: ") and len(str(e.value)) < 600


def test_claim_value_at_is_checked():
    body = (CLAIM.replace('check = "arithmetic"\n', 'experiment = "e"\n')
            + 'values.a = {cells = "", sample = "x", at = "steps=1e999"}\nmeasured = "a"\n'
              'passes = "a > 0"\n')
    with pytest.raises(UserError, match=r"claim B-9-a: values.a: bad at = 'steps=1e999'"):
        parse_claims(f"[[claim]]\n{body}", "x.toml")


SECTION_HEAD = 'name = "s"\ntitle = "s"\nreference = "none"\nt_end = 50.0\n'
SECTION_GROUP = '[[cells]]\nproblems = ["henon-heiles"]\nmethods = ["rk4:h=0.1"]\n'


@pytest.mark.parametrize("text, refused", [
    (SECTION_HEAD + "section = 2\nevery = 3\n" + SECTION_GROUP, True),
    (SECTION_HEAD + SECTION_GROUP + "section = 2\nevery = 3\n", True),
    (SECTION_HEAD + "section = 2\n" + SECTION_GROUP + "every = 3\n", True),
    (SECTION_HEAD + "every = 3\n" + SECTION_GROUP + "section = 2\n", False),   # top's default
    (SECTION_HEAD + SECTION_GROUP + "section = 2\nevery = 1\n", False),
])
def test_every_beside_a_section_is_refused(text, refused):
    """A section cell writes every crossing: an ``every`` beside its ``section`` was dropped
    without a word (``gnibench solve --every 3 --section 2`` is refused); a top-level every is the
    default of the other groups, left aside by a group with its own section."""
    from gnibench.suite.runs.experiment import parse_experiment

    if refused:
        with pytest.raises(UserError, match="section and every = 3 both given"):
            parse_experiment(text, "s.toml")
    else:
        cells = parse_experiment(text, "s.toml").cells
        assert len(cells) == 1 and cells[0].section == 2


def test_an_option_varied_twice_is_refused_not_dropped():
    """vary.h and vary.method.h name the same option: before, one list silently won (one cell of
    h = 0.3 instead of the product)."""
    text = ('name = "v"\ntitle = "t"\nreference = "r"\nsteps = 10\n[[cells]]\n'
            'problems = ["kepler-2d"]\nmethods = ["rk4"]\nvary.h = [0.1, 0.2]\nvary.method.h = [0.3]\n')
    with pytest.raises(UserError, match=r"vary.method.h: the option 'h' of the method is varied "
                                        r"twice"):
        parse_experiment(text, "v.toml", "paper")


def test_a_byte_order_mark_is_not_part_of_the_file(tmp_path, capsys):
    """A UTF-8 BOM at the start (some Windows editors write one) read as "Invalid statement (at
    line 1, column 1)"; the file is read without it."""
    exp = tmp_path / "bom.toml"
    exp.write_bytes(b"\xef\xbb\xbf" + ('name = "bom"\ntitle = "t"\nreference = "r"\nsteps = 4\n'
                                       '[[cells]]\nproblems = ["kepler-2d"]\nmethods = ["rk4:h=0.1"]\n'
                                       ).encode())
    assert main(["run", str(exp), "-o", str(tmp_path / "out"), "-j", "1", "--no-report"]) == 0
    assert "1 cells" in capsys.readouterr().err
