"""The store's cell key is complete and canonical: a property of the public key function.

A results directory reuses a stored cell whose key matches (:func:`gnibench.suite.runs.store.
cell_key`), so the key must change with everything that determines the cell's numbers, and with
nothing else. From one canonical cell of each kind (adaptive with a time grid, fixed-step, a
Poincaré section, a user-defined problem loaded from a file), every field is perturbed in turn:
the problem and its options, the method and its options, its modifiers, steps, t_end, every,
dt_out, section, metrics, reference solution, the loaded definitions and their files' content.
Each perturbed cell must get a key of its own (all keys distinct); the cell's place in its
experiment (id, group, label), the experiment's name, title and description, and the spelling
of the same specs (option order, number format, defaults written out) must not change it.
"""
from __future__ import annotations

import pytest
from gnibench.suite.runs.experiment import load_experiment
from gnibench.suite.runs.store import cell_key

ADAPTIVE = dict(problems='["kepler-2d:e=0.5"]', methods='["dopri5:rtol=1e-08,atol=1e-10"]',
                t_end="10.0", every="2", dt_out="0.5", metrics='["growth"]',
                reference_solution='"exact"')
FIXED = dict(problems='["pendulum"]', methods='["stormer-verlet:h=0.1"]', steps="20", every="5")
SECTION = dict(problems='["henon-heiles"]', methods='["rk4:h=0.05"]', steps="200",
               section="3")
USER = dict(problems='["my-osc"]', methods='["rk4:h=0.1"]', steps="20")
OSC = ('[[problem]]\nid = "my-osc"\nstates = ["q", "p"]\nhamiltonian = "p^2/2 + {k}*q^2/2"\n'
       'initial = {{q = 1, p = 0}}\n')
TOP = ("t_end", "steps", "every", "dt_out", "section", "metrics", "reference_solution")


def key_of(tmp_path, fields: dict, name="k", title="t", label="", defs=None, position=0,
           description="") -> str:
    """The key of the first cell of an experiment written from ``fields`` (top-level keys and
    one [[cells]] group), optionally after ``position`` other groups and with a definitions file
    of content ``defs``."""
    head = [f'name = "{name}"', f'title = "{title}"', 'reference = "[HLW] I.1"',
            f'description = "{description}"']
    head += [f"{k} = {v}" for k, v in fields.items() if k in TOP]
    if defs is not None:
        (tmp_path / "defs.toml").write_text(defs)
        head.append('load = ["defs.toml"]')
    group = [f'label = "{label}"', f"problems = {fields['problems']}",
             f"methods = {fields['methods']}"]
    before = "".join(f'[[cells]]\nproblems = {fields["problems"]}\nmethods = ["euler:h=0.0{k + 1}"]\n'
                     for k in range(position))
    text = "\n".join(head) + "\n" + before + "[[cells]]\n" + "\n".join(group) + "\n"
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    cells = load_experiment(path).cells
    return cell_key(cells[position])


def perturbations(base: dict, kind: str) -> dict[str, dict]:
    """Every field of ``base`` changed once (what must change the key)."""
    option = {"adaptive": '"kepler-2d:e=0.6"', "fixed": '"pendulum:q0=0.5"',
              "section": '"henon-heiles:H0=0.1"'}[kind]
    other = {"adaptive": '"kepler-3d"', "fixed": '"harmonic-oscillator"',
             "section": '"gavrilov-shilnikov"'}[kind]
    out = {"problem option": {**base, "problems": f"[{option}]"},
           "problem": {**base, "problems": f"[{other}]"}}
    if kind == "adaptive":
        out["method"] = {**base, "methods": '["dop853:rtol=1e-08,atol=1e-10"]'}
        out["method option rtol"] = {**base, "methods": '["dopri5:rtol=1e-09,atol=1e-10"]'}
        out["method option atol"] = {**base, "methods": '["dopri5:rtol=1e-08,atol=1e-11"]'}
        out["rtol and atol swapped"] = {**base, "methods": '["dopri5:rtol=1e-10,atol=1e-08"]'}
        out["method summation"] = {**base,
                                   "methods": '["dopri5:rtol=1e-08,atol=1e-10,sum=compensated"]'}
        out["modifier"] = {**base, "methods": '["dopri5:rtol=1e-08,atol=1e-10+projection:on=H"]'}
        out["t_end"] = {**base, "t_end": "11.0"}
        out["dt_out"] = {**base, "dt_out": "0.25"}
        out["no dt_out"] = {k: v for k, v in base.items() if k != "dt_out"}
        out["metrics"] = {**base, "metrics": '["growth", "precession"]'}
        out["metric option"] = {**base, "metrics": '["growth:window=0.5/1"]'}
        out["reference"] = {**base, "reference_solution": '"heyoka"'}
        out["every"] = {**base, "every": "3"}
    else:
        method = {"fixed": ("stormer-verlet", "symplectic-euler"),
                  "section": ("rk4", "euler")}[kind]
        out["method"] = {**base, "methods": base["methods"].replace(*method)}
        out["method option h"] = {**base, "methods": base["methods"].replace("h=0.", "h=0.0")}
        out["modifier"] = {**base, "methods": base["methods"].replace('"]', '+observer:on=H"]')}
        out["steps"] = {**base, "steps": "21"}
        out["t_end instead of steps"] = {**{k: v for k, v in base.items() if k != "steps"},
                                        "t_end": "2.0"}
        if kind == "section":
            out["section"] = {**base, "section": "4"}
        else:
            out["every"] = {**base, "every": "4" if base.get("every") != "4" else "2"}
    return out


@pytest.mark.parametrize("kind,base", [("adaptive", ADAPTIVE), ("fixed", FIXED),
                                       ("section", SECTION)])
def test_every_field_changes_the_key(tmp_path, kind, base):
    keys = {"canonical": key_of(tmp_path, base)}
    for what, fields in perturbations(base, kind).items():
        keys[what] = key_of(tmp_path, fields)
    seen: dict[str, str] = {}
    for what, key in keys.items():
        assert key not in seen, f"{what!r} has the key of {seen.get(key)!r}"
        seen[key] = what


def test_loaded_definitions_and_their_content_are_in_the_key(tmp_path):
    """A user problem: its definition file's content (a coefficient) and another problem of the
    same id in another file give other keys; the same content loaded again, the same key."""
    osc = key_of(tmp_path, USER, defs=OSC.format(k=1))
    assert key_of(tmp_path, USER, defs=OSC.format(k=1)) == osc
    assert key_of(tmp_path, USER, defs=OSC.format(k=2)) != osc
    assert key_of(tmp_path, USER, defs=OSC.format(k=1).replace("q = 1", "q = 0.5")) != osc
    assert key_of(tmp_path, {**USER, "methods": '["euler:h=0.1"]'}, defs=OSC.format(k=1)) != osc


@pytest.mark.parametrize("kind,base", [("adaptive", ADAPTIVE), ("fixed", FIXED),
                                       ("section", SECTION)])
def test_nothing_else_changes_the_key(tmp_path, kind, base):
    """The cell's place and labels, the experiment's names, and the spelling of the same specs."""
    key = key_of(tmp_path, base)
    assert key_of(tmp_path, base, name="other", title="another title", description="x") == key
    assert key_of(tmp_path, base, label="a label") == key
    assert key_of(tmp_path, base, position=2) == key               # other cell id and group
    if kind == "adaptive":
        same = {**base, "methods": '["dopri5:atol=1e-10,rtol=1e-8"]',      # order, spelling
                "problems": '["kepler-2d:e=0.50"]', "t_end": "10", "dt_out": "5e-1"}
        assert key_of(tmp_path, same) == key
    elif kind == "fixed":
        same = {**base, "methods": '["stormer-verlet:h=1e-1"]', "every": "05"[1:]}
        assert key_of(tmp_path, same) == key
