"""The deck format as a JSON Schema (draft 2020-12), generated from the dataclasses."""

from __future__ import annotations

import dataclasses
import types
from typing import Any, Union, get_args, get_origin

from icewall.deck.fields import default_of, hints_of, is_required
from icewall.deck.schema import FORMAT_VERSION, Deck


def _json_default(value: Any) -> Any:
    if dataclasses.is_dataclass(value):
        return dataclasses.asdict(value)
    if isinstance(value, tuple):
        return list(value)
    return value


def _type_schema(tp: Any, meta: dict) -> dict:
    origin = get_origin(tp)
    if origin in (Union, types.UnionType):
        inner = [a for a in get_args(tp) if a is not type(None)][0]
        return {"anyOf": [_type_schema(inner, meta), {"type": "null"}]}
    if dataclasses.is_dataclass(tp):
        return _object_schema(tp)
    if origin in (list, tuple):
        return {"type": "array", "items": _type_schema(get_args(tp)[0], meta)}
    out: dict[str, Any] = {float: {"type": "number"}, int: {"type": "integer"},
                           bool: {"type": "boolean"}, str: {"type": "string"}}[tp].copy()
    if meta.get("choices"):
        out["enum"] = list(meta["choices"])
    for key, name in (("minimum", "minimum"), ("maximum", "maximum"),
                      ("exclusive_minimum", "exclusiveMinimum")):
        if meta.get(key) is not None:
            out[name] = meta[key]
    return out


def _object_schema(cls: type) -> dict:
    hints = hints_of(cls)
    properties, required = {}, []
    for fld in dataclasses.fields(cls):
        meta = dict(fld.metadata)
        prop = _type_schema(hints[fld.name], meta)
        doc = meta.get("doc", "")
        prop["description"] = doc + (f" [{meta['unit']}]" if meta.get("unit") else "")
        if is_required(fld):
            required.append(fld.name)
        else:
            prop["default"] = _json_default(default_of(fld))
        properties[fld.name] = prop
    out = {"type": "object", "properties": properties, "additionalProperties": False}
    if cls.__doc__ and not cls.__doc__.startswith(cls.__name__ + "("):
        out["description"] = cls.__doc__.strip().splitlines()[0]
    if required:
        out["required"] = required
    return out


def deck_json_schema() -> dict:
    """JSON Schema of deck format v1."""
    schema = _object_schema(Deck)
    schema.update({"$schema": "https://json-schema.org/draft/2020-12/schema",
                   "$id": f"https://icewall.invalid/deck-v{FORMAT_VERSION}.schema.json",
                   "title": f"icewall deck, format version {FORMAT_VERSION}"})
    return schema
