"""The spec syntax: canonical texts round-trip, numbers with exponents, lists, modifiers.

Grammar (suite/spec.py): ``PROBLEM := id[:key=value,...]``, ``METHOD := base[:opts]{+modifier[:opts]}``,
lists ``a/b/c``; a ``+`` starts a modifier only when a letter follows, so ``1e+6`` is a number.
Every record of every registry is exercised with non-default values generated from its own
parameter schema (awkward floats such as 0.1 + 0.2 whose shortest repr is 17 digits). The option
values stand for the quantities of the seeds (h of [HLW] (1.5)-(1.17), θ of [B] (2.6), H0 of
[B] (2.5)), but the checks here are purely syntactic.
"""
from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from gnibench.methods import METHODS, MODIFIERS
from gnibench.problems import REGISTRY
from gnibench.suite.cell.spec import parse_method, parse_problem, split_method
from gnibench.suite.foundation.params import format_float

MOD_PROBLEM = "double-oscillator"          # two independent integrals H1, H2 ([B] (4.2))
ODD = (0.1 + 0.2) - 0.3                    # 5.551115123125783e-17: a float with a long repr


def _nudge(v: float, low=None, high=None, low_open=False, high_open=False) -> float:
    """A value near v, different from it, inside the range, with a long shortest repr."""
    for step in (1, -1):
        w = v + step * (1 / 3) * 1e-3 * max(1.0, abs(v))
        if low is not None and (w < low or (low_open and w == low)):
            continue
        if high is not None and (w > high or (high_open and w == high)):
            continue
        return w
    raise AssertionError(f"cannot nudge {v} inside [{low}, {high}]")


def _value_text(p, default_point=None) -> list[str]:
    """Candidate non-default texts for one parameter (several for choices/bools)."""
    rng = {"low": p.low, "high": p.high, "low_open": p.low_open, "high_open": p.high_open}
    if p.kind == "bool":
        return ["false" if p.default else "true"]
    if p.kind == "str":
        return list(p.choices) if p.choices else ["text"]
    if p.kind == "int":
        base = p.default if p.default is not None else (p.low or 0)
        v = base + 1 if p.high is None or base + 1 <= p.high else base - 1
        return [str(v)]
    if p.kind == "float":
        base = p.default if p.default is not None else default_point
        if base is None:
            base = 0.5 if p.low is None or p.low <= 0.5 else p.low + 0.5
        return [repr(_nudge(float(base), **rng))]
    if p.kind == "floats":
        base = p.default[0] if p.default else 1.0
        return [repr(_nudge(float(base), **rng))]
    raise AssertionError(f"no generator for kind {p.kind}")


def _relevant(p, chosen) -> bool:
    return p.only_if is None or chosen.get(p.only_if[0], None) == p.only_if[1]


def _option_sets(record, default_point=None, extra=None):
    """Dicts name -> text: every choice of each str/bool option, the others non-default."""
    params = [p for p in record.params if p.kind != "names"]
    multi = [p for p in params if p.kind in ("str", "bool")]
    out = []
    for combo in itertools.product(*[_value_text(p) for p in multi]) or [()]:
        chosen_raw = {p.name: v for p, v in zip(multi, combo)}
        typed = {p.name: p.parse(v, "test") for p, v in zip(multi, combo)}
        opts = {}
        for p in params:
            if p.name in chosen_raw:
                opts[p.name] = chosen_raw[p.name]
            elif _relevant(p, typed):
                opts[p.name] = _value_text(p, (default_point or {}).get(p.name))[0]
        opts = {k: v for k, v in opts.items() if _relevant(record_param(record, k), typed)}
        opts.update(extra or {})
        out.append(opts)
    return out


def record_param(record, name):
    return next(p for p in record.params if p.name == name)


def _spec(rid, opts) -> str:
    return rid + (":" + ",".join(f"{k}={v}" for k, v in opts.items()) if opts else "")


def _problem_cases():
    cases = []
    for pid, rec in REGISTRY.items():
        defaults = {p.name: p.default for p in rec.params}
        y0 = rec.y0(defaults)
        point = {f"{s}0": v for s, v in zip(rec.state, y0)}
        for opts in _option_sets(rec, point):
            cases.append(pytest.param(_spec(pid, opts), id=pid))
    return cases


def _method_cases():
    cases = []
    for mid, rec in METHODS.items():
        for k, opts in enumerate(_option_sets(rec)):
            cases.append(pytest.param(_spec(mid, opts), id=f"{mid}-{k}"))
    return cases


def _modifier_cases():
    cases = []
    for mid, rec in MODIFIERS.items():
        for k, opts in enumerate(_option_sets(rec, extra={"on": "H1/H2"})):
            # lists: one value per observed integral for the floats options
            opts = {key: (f"{v}/{_nudge(float(v))!r}" if record_param(rec, key).kind == "floats"
                          else v) for key, v in opts.items()}
            cases.append(pytest.param(f"rk4:h={ODD!r}+{_spec(mid, opts)}", id=f"{mid}-{k}"))
    return cases


@pytest.mark.parametrize("spec", _problem_cases())
def test_problem_canonical_text_round_trips(spec):
    """parse -> text -> parse -> text is a fixed point and the values are identical."""
    a = parse_problem(spec)
    b = parse_problem(a.text())
    assert b.text() == a.text()
    assert b.values == a.values
    given = dict(kv.split("=") for kv in spec.partition(":")[2].split(",") if kv)
    for k, v in given.items():                  # every given value survives, exactly
        assert a.values[k] == record_param(a.record, k).parse(v, "test")


def _method_roundtrip(spec, problem=None):
    a = parse_method(spec, problem)
    b = parse_method(a.text(), problem)
    assert b.text() == a.text()
    assert b.base.values == a.base.values
    assert [m.values for m in b.modifiers] == [m.values for m in a.modifiers]
    return a


@pytest.mark.parametrize("spec", _method_cases())
def test_method_canonical_text_round_trips(spec):
    """Every method, with every option at a non-default value (h of [HLW] (1.5)-(1.17))."""
    a = _method_roundtrip(spec)
    assert a.modifiers == ()
    assert "h" not in a.base.values or a.base.values.get("h") is None or a.base.values["h"] > 0


@pytest.mark.parametrize("spec", _modifier_cases())
def test_modifier_canonical_text_round_trips(spec):
    """Every modifier and mode, with per-integral lists (θ_i of [B] (2.6), H0 of (2.5))."""
    a = _method_roundtrip(spec, parse_problem(MOD_PROBLEM))
    assert len(a.modifiers) == 1
    m = a.modifiers[0]
    assert m.values["on"] == ("H1", "H2")
    for p in m.record.params:
        if p.kind == "floats" and m.values[p.name] is not None:
            assert len(m.values[p.name]) == 2


@pytest.mark.parametrize("text,h,nmods", [
    ("rk4:h=1e+0", 1.0, 0),
    ("rk4:h=2.5e+3", 2500.0, 0),
    ("rk4:h=1E+2", 100.0, 0),
    ("rk4:h=1e-3", 0.001, 0),
    ("rk4:h=1e+0+observer", 1.0, 1),
    ("rk4:h=1e+0+observer:theta=1e+2+penalty:theta=2E+1", 1.0, 2),
])
def test_exponent_plus_is_a_number_not_a_modifier(text, h, nmods):
    """``+`` followed by a digit stays inside the number; ``+`` followed by a letter starts a modifier."""
    cfg = parse_method(text, parse_problem("harmonic-oscillator"))
    assert cfg.base.values["h"] == h
    assert len(cfg.modifiers) == nmods
    assert len(split_method(text)) == nmods + 1


def test_modifier_values_with_exponents():
    cfg = parse_method("rk4:h=1e+0+observer:theta=1e+2+penalty:theta=2E+1/3e+0,on=H1/H2",
                       parse_problem("double-oscillator"))
    assert [m.id for m in cfg.modifiers] == ["observer", "penalty"]
    assert cfg.modifiers[0].values["theta"] == (100.0, 100.0)      # one value for both integrals
    assert cfg.modifiers[1].values["theta"] == (20.0, 3.0)
    assert cfg.modifiers[1].values["on"] == ("H1", "H2")


def test_lists_with_slash():
    cfg = parse_method("euler:h=0.001+observer:on=H2/H1,theta=1/2.5,H0=1.5/1.9",
                       parse_problem("double-oscillator"))
    m = cfg.modifiers[0]
    assert m.values["on"] == ("H2", "H1")
    assert m.values["theta"] == (1.0, 2.5)
    assert m.values["H0"] == (1.5, 1.9)
    assert "on=H2/H1" in cfg.text() and "theta=1/2.5" in cfg.text() and "H0=1.5/1.9" in cfg.text()


def test_plus_letter_split():
    assert split_method("rk4:h=0.1+observer:theta=2+penalty") == ["rk4:h=0.1", "observer:theta=2", "penalty"]
    assert split_method("rk4:h=1e+6") == ["rk4:h=1e+6"]
    assert split_method("rk4:h=1e+6+observer:H0=-1e+2") == ["rk4:h=1e+6", "observer:H0=-1e+2"]


def test_format_float_round_trips():
    """Canonical floats are the shortest text that parses back to the same double."""
    rng = np.random.default_rng(7)
    values = [ODD, 0.1, 1e22, 1e-300, 5e-324, 2.0**-1074, 123456789.123456789, math.pi, -0.0]
    values += list(10.0 ** rng.uniform(-30, 30, 200) * rng.choice([-1, 1], 200))
    for v in values:
        text = format_float(v)
        assert float(text) == v and math.copysign(1, float(text)) == math.copysign(1, v)
        assert not text.endswith(".0")
        assert len(text) <= len(repr(float(v)))
    spec = parse_method(f"rk4:h={format_float(1e22)}")
    assert spec.text() == "rk4:h=1e+22" and parse_method(spec.text()).base.values["h"] == 1e22
