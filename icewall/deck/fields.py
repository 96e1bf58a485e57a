"""Typed deck options: `option()` declares one (default, unit, doc, limits) on a frozen
dataclass, and `build()` turns a parsed YAML tree into those dataclasses with errors that name
the file, line and key path.
"""

from __future__ import annotations

import dataclasses
import types
import typing
from dataclasses import MISSING
from typing import Any, Union, get_args, get_origin, get_type_hints

from icewall.deck.yamlsrc import LineDict, LineList, short_repr
from icewall.errors import DeckError

REQUIRED = MISSING


def option(default: Any = REQUIRED, *, doc: str, unit: str = "", choices: tuple = (),
           minimum: float | None = None, maximum: float | None = None,
           exclusive_minimum: float | None = None) -> Any:
    """A documented deck option; list/dataclass defaults are copied per instance."""
    meta = {"doc": doc, "unit": unit, "choices": tuple(choices), "minimum": minimum,
            "maximum": maximum, "exclusive_minimum": exclusive_minimum}
    if default is REQUIRED:
        return dataclasses.field(metadata=meta)
    if isinstance(default, list):
        return dataclasses.field(default_factory=lambda: tuple(default), metadata=meta)
    if dataclasses.is_dataclass(default):
        return dataclasses.field(default_factory=lambda: default, metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


class Context:
    """Where we are in the deck: file name and key path, for messages."""

    def __init__(self, file: str) -> None:
        self.file = file

    def error(self, message: str, line: int | None, path: str) -> DeckError:
        return DeckError(message, self.file, line, path or None)


def _type_name(tp: Any) -> str:
    origin = get_origin(tp)
    if tp is float:
        return "a number"
    if tp is int:
        return "an integer"
    if tp is bool:
        return "true or false"
    if tp is str:
        return "a string"
    if origin in (list, tuple):
        return "a list"
    if dataclasses.is_dataclass(tp):
        return "a mapping"
    return str(tp)


def _optional_inner(tp: Any) -> Any | None:
    origin = get_origin(tp)
    if origin in (Union, types.UnionType):
        args = [a for a in get_args(tp) if a is not type(None)]
        if len(args) == 1 and type(None) in get_args(tp):
            return args[0]
    return None


def _convert(value: Any, tp: Any, meta: dict, ctx: Context, line: int | None, path: str) -> Any:
    inner = _optional_inner(tp)
    if inner is not None:
        return None if value is None else _convert(value, inner, meta, ctx, line, path)
    if value is None:
        raise ctx.error(f"a value is required ({_type_name(tp)})", line, path)
    origin = get_origin(tp)
    if dataclasses.is_dataclass(tp):
        if not isinstance(value, dict):
            raise ctx.error(f"expected a mapping, got {short_repr(value)}", line, path)
        return build(tp, value, ctx, path)
    if origin in (list, tuple):
        if not isinstance(value, list):
            raise ctx.error(f"expected a list, got {short_repr(value)}", line, path)
        (item_tp, *_) = get_args(tp)
        lines = value.line_of if isinstance(value, LineList) else (lambda i: line)
        return tuple(_convert(v, item_tp, meta, ctx, lines(i), f"{path}[{i}]")
                     for i, v in enumerate(value))
    if tp is bool:
        if not isinstance(value, bool):
            raise ctx.error(f"expected true or false, got {short_repr(value)}", line, path)
        return value
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ctx.error(f"expected a number, got {short_repr(value)}", line, path)
        try:
            value = float(value)
        except OverflowError:  # an integer with hundreds of digits
            raise ctx.error(f"{short_repr(value, 20)} is too large for a number", line,
                            path) from None
        if value != value or value in (float("inf"), float("-inf")):
            raise ctx.error("expected a finite number", line, path)
    elif tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ctx.error(f"expected an integer, got {short_repr(value)}", line, path)
    elif tp is str:
        if not isinstance(value, str):
            raise ctx.error(f"expected a string, got {short_repr(value)}", line, path)
        if "\x00" in value:
            raise ctx.error("a NUL character is not allowed in a string", line, path)
        try:
            value.encode("utf-8")
        except UnicodeEncodeError as exc:  # an escaped lone surrogate ("\ud83e")
            raise ctx.error(f"character U+{ord(value[exc.start]):04X} at {exc.start} is half "
                            "of a surrogate pair, not text (write the character itself)",
                            line, path) from None
    _check_limits(value, meta, ctx, line, path)
    return value


def _check_limits(value: Any, meta: dict, ctx: Context, line: int | None, path: str) -> None:
    unit = f" {meta['unit']}" if meta.get("unit") else ""
    shown = short_repr(value, 24)
    if meta.get("choices") and value not in meta["choices"]:
        allowed = ", ".join(repr(c) for c in meta["choices"])
        raise ctx.error(f"{short_repr(value)} is not one of {allowed}", line, path)
    if meta.get("minimum") is not None and value < meta["minimum"]:
        raise ctx.error(f"{shown}{unit} is below the minimum {meta['minimum']}{unit}", line, path)
    if meta.get("maximum") is not None and value > meta["maximum"]:
        raise ctx.error(f"{shown}{unit} is above the maximum {meta['maximum']}{unit}", line, path)
    low = meta.get("exclusive_minimum")
    if low is not None and value <= low:
        raise ctx.error(f"{shown}{unit} must be greater than {low}{unit}", line, path)


def build(cls: type, data: dict, ctx: Context, path: str = "") -> Any:
    """Convert a parsed mapping into dataclass `cls`, checking keys, types and limits."""
    hints = get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    line_of = data.line_of if isinstance(data, LineDict) else (lambda key: None)
    for key in data:
        if key not in fields:
            known = ", ".join(fields)
            raise ctx.error(f"unknown key (allowed here: {known})", line_of(key),
                            f"{path}.{key}" if path else key)
    kwargs = {}
    for name, fld in fields.items():
        sub = f"{path}.{name}" if path else name
        if name in data:
            kwargs[name] = _convert(data[name], hints[name], dict(fld.metadata), ctx,
                                    line_of(name), sub)
        elif fld.default is MISSING and fld.default_factory is MISSING:
            where = getattr(data, "line", None)
            raise ctx.error("required key is missing", where, sub)
    return cls(**kwargs)


def is_required(fld: dataclasses.Field) -> bool:
    return fld.default is MISSING and fld.default_factory is MISSING


def default_of(fld: dataclasses.Field) -> Any:
    if fld.default is not MISSING:
        return fld.default
    if fld.default_factory is not MISSING:
        return fld.default_factory()
    return None


def hints_of(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)
