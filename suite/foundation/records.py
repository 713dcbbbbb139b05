"""Typed records for the input files (experiments, figure specs, scales, claims), and their errors.

Every TOML input is described by a :class:`Record`: a pydantic v2 model in strict mode
(``extra="forbid"``: unknown keys are refused; no coercion: ``1.5`` is not an integer, ``true``
is not a number, a string is not a list; ``allow_inf_nan=False``), whose fields carry their type,
bounds, sizes, default, an :class:`Allowed` text (what the error says is allowed) and a
description. The schemas live in one place each (``suite/runs/experiment_schema.py``,
``suite/runs/figure_schema.py``, ``suite/ledger/entries.py``); a new key is one line there; the
documentation's tables of keys are rendered from them (:func:`markdown_table`).

Why pydantic v2 rather than msgspec: pydantic's errors are structured (the location of the key as
a tuple, the offending input, the violated bound), which is what one line naming the file, the
path of the key and what is allowed needs; msgspec reports one formatted string. Field and model
validators let the semantics that need the registries (spec strings, metric choices, cross-key
rules) run inside the same validation with the same error path, and the field metadata
(constraints, descriptions) is introspectable for the documentation's tables. Speed is irrelevant here
(files of a few kB, validated once).

:func:`validate` turns a :class:`pydantic.ValidationError` into one :class:`UserError` line::

    my.toml: cells[0]: bad steps = 0; allowed: an integer from 1 to 2^62
    my.toml: cells[0]: unknown key 'metods'; did you mean 'methods'? (known: ...)
    my.toml: figure.panels[1]: missing key 'y' (a column of samples.parquet)

never a multi-line dump; the offending value is shortened (a 400-digit integer is shown by its
size). Validators raise ``ValueError(message)``; the message follows the key's path.
"""
from __future__ import annotations

import types
import typing
from dataclasses import dataclass
from typing import Annotated

from gnibench.suite.foundation.budgets import INT_LIMIT
from gnibench.suite.foundation.errors import UserError, unknown
from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationError
from pydantic_core import PydanticCustomError, PydanticUndefined

MAX_TEXT = 100_000        # characters of one text value (a description, a note)
MAX_LINE = 2_000          # characters of a one-line value (a title, a label, a spec)
MAX_ITEMS = 10_000        # items of one list


@dataclass(frozen=True)
class Allowed:
    """What a key allows, in words (the error message and the documentation's table say it)."""

    text: str


class Record(BaseModel):
    """A validated table of an input file: strict types, no unknown keys, immutable."""

    model_config = ConfigDict(strict=True, extra="forbid", frozen=True, allow_inf_nan=False,
                              validate_default=False)

    def given(self, key: str) -> bool:
        """Whether the file gave ``key`` (rather than its default)."""
        return key in self.model_fields_set


def refuse():
    """Raised by a validator whose value is simply not allowed: the error line then says
    ``bad <key> = <value>; allowed: <the key's allowed text>``."""
    return PydanticCustomError("bad_value", "not allowed")


def _one_line(value: str) -> str:
    if not value.isprintable():
        raise refuse()
    return value


def _non_empty(value: str) -> str:
    if not value.strip():
        raise refuse()
    return value


def via(check):
    """A validator from one of our checks that raises UserError (its message goes in the line)."""
    def run(value):
        try:
            out = check(value)
        except UserError as e:
            raise ValueError(str(e)) from None
        return value if out is None else out
    return run


#: common field types (each says what it allows)
Text = Annotated[str, Allowed("a string"), Field(max_length=MAX_TEXT)]
Line = Annotated[str, Allowed("one line of text"), Field(max_length=MAX_LINE),
                 AfterValidator(_one_line)]
NonEmptyLine = Annotated[str, Allowed("one line of non-empty text"), Field(max_length=MAX_LINE),
                         AfterValidator(_one_line), AfterValidator(_non_empty)]
Count = Annotated[int, Allowed("an integer from 1 to 2^62"), Field(ge=1, le=INT_LIMIT)]
Number = Annotated[float, Allowed("a finite number")]
Positive = Annotated[float, Allowed("a finite number > 0"), Field(gt=0)]


def key(default=PydanticUndefined, doc: str = "", allowed: str | None = None, **constraints):
    """A field: its default (none: required), its description, what it allows (when not the
    type's own text), and pydantic constraints (``ge``, ``le``, ``min_length``, ...)."""
    extra = {"allowed": allowed} if allowed else None
    return Field(default, description=doc, json_schema_extra=extra, **constraints)


def short(value) -> str:
    """A short repr of a user value for an error line (huge integers by their size)."""
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 64:
        return f"<an integer of {value.bit_length()} bits>"
    if isinstance(value, (list, tuple)) and len(value) > 6:
        return "[" + ", ".join(short(v) for v in value[:5]) + f", ... ({len(value)} items)]"
    if isinstance(value, dict) and len(value) > 6:
        return "{" + ", ".join(f"{k!r}: {short(v)}" for k, v in list(value.items())[:5]) + ", ...}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(short(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{short(k)}: {short(v)}" for k, v in value.items()) + "}"
    text = repr(value)
    return text if len(text) <= 80 else text[:60] + "..." + text[-10:]


def validate(record: type[Record], data, where: str):
    """``record`` validated from ``data`` (a parsed TOML table); one UserError line otherwise."""
    try:
        return record.model_validate(data)
    except ValidationError as e:
        raise UserError(error_line(record, e.errors(include_url=False)[0], where)) from None


def _path(loc) -> str:
    out = ""
    for part in loc:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


def error_line(record: type[Record], error: dict, where: str) -> str:
    """One line for one pydantic error: the file, the path of the key, what is wrong and what is
    allowed."""
    loc = tuple(p for p in error["loc"] if p != "[key]")
    keys = [i for i, p in enumerate(loc) if isinstance(p, str)]
    cut = keys[-1] if keys else len(loc)
    parent, leaf = _path(loc[:cut]), _path(loc[cut:])
    head = f"{where}: {parent}" if parent else where
    kind = error["type"]
    if kind == "extra_forbidden":
        model = _model_at(record, loc[:cut])
        known = tuple(fields(model)) if model else ()
        return f"{head}: {unknown('key', str(loc[cut]), known)}"
    info = _field_at(record, loc)
    allowed = allowed_text(info) if info is not None else ""
    if kind == "missing":
        return f"{head}: missing key {leaf!r}" + (f" ({allowed})" if allowed else "")
    if kind in ("value_error", "assertion_error"):
        message = str(error.get("ctx", {}).get("error", error["msg"]))
        plain = not leaf or message.startswith((leaf, f"bad {leaf}"))
        return f"{head}: {message}" if plain else f"{head}: {leaf}: {message}"
    detail = f"; allowed: {allowed}" if allowed else f" ({error['msg'].lower()})"
    return f"{head}: bad {leaf or 'value'} = {short(error.get('input'))}{detail}"


def _unwrap(tp):
    """The record type or container a field annotation stands for (Annotated, Optional dropped)."""
    while True:
        origin = typing.get_origin(tp)
        if origin is Annotated:
            tp = typing.get_args(tp)[0]
        elif origin in (typing.Union, types.UnionType):
            args = [a for a in typing.get_args(tp) if a is not type(None)]
            if len(args) != 1:
                return tp
            tp = args[0]
        else:
            return tp


def _walk(record, loc):
    """(the last field's FieldInfo, the type at the end of ``loc``) walking from ``record``."""
    tp, info = record, None
    for part in loc:
        tp = _unwrap(tp)
        origin, args = typing.get_origin(tp), typing.get_args(tp)
        if isinstance(tp, type) and issubclass(tp, BaseModel) and isinstance(part, str):
            info = fields(tp).get(part)
            if info is None:
                return info, None
            tp = info.annotation
        elif origin in (list, tuple) and isinstance(part, int) and args:
            tp = args[0]
        elif origin is dict and args:
            tp = args[1]
        else:
            return info, None
    return info, _unwrap(tp)


def fields(model) -> dict:
    """The keys of a record as written in the file (aliases such as ``list``) -> FieldInfo."""
    return {info.alias or name: info for name, info in model.model_fields.items()}


def _field_at(record, loc):
    return _walk(record, loc)[0]


def _model_at(record, loc):
    tp = _walk(record, loc)[1]
    return tp if isinstance(tp, type) and issubclass(tp, BaseModel) else None


def allowed_text(info) -> str:
    """What a field allows, in words: its own ``allowed`` text, else its type's."""
    extra = info.json_schema_extra if isinstance(info.json_schema_extra, dict) else {}
    if extra.get("allowed"):
        return extra["allowed"]
    for meta in reversed(info.metadata):          # the outermost Annotated says it best
        if isinstance(meta, Allowed):
            return meta.text
    return _type_words(info.annotation)


def _type_words(tp) -> str:
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin is Annotated:
        found = [m.text for m in args[1:] if isinstance(m, Allowed)]
        return found[-1] if found else _type_words(args[0])
    if origin is typing.Literal:
        return " | ".join(str(a) for a in args)
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_type_words(a) for a in args if a is not type(None))
    if origin is list:
        return f"a list of {_type_words(args[0])}" if args else "a list"
    if origin is dict:
        return f"a table of {_type_words(args[1])}" if args else "a table"
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return f"a table ({', '.join(fields(tp))})"
    return {bool: "true | false", int: "an integer", float: "a finite number",
            str: "a string"}.get(tp, getattr(tp, "__name__", str(tp)))


def markdown_table(record: type[Record], prefix: str = "") -> str:
    """The keys of a record as a Markdown table: key, allowed values, default, meaning."""
    rows = ["| key | allowed | default | meaning |", "|---|---|---|---|"]
    keys = sorted(fields(record).items(), key=lambda item: not item[1].is_required())
    for name, info in keys:
        default = ("required" if info.is_required() else "" if info.default in (None, "", (), [], {})
                   else f"`{_toml(info.default)}`")
        rows.append(f"| `{prefix}{name}` | {_cell(allowed_text(info))} | {default} | "
                    f"{_cell(info.description or '')} |")
    return "\n".join(rows) + "\n"


def _toml(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return str(value)


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")
