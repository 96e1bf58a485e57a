"""Reading a compare baseline through the deck's error path (issue 38, item 5): the deck's YAML
reader (lines kept; control characters, nesting deeper than 64, integers too long for a number
and duplicate keys refused), then every value the comparison reads checked for its type and a
finite value. Any problem is one line naming the file, the line and the key (exit 2); a value
such as ``.nan`` or ``.inf`` is never a figure. Keys it does not know are left alone (a newer
icewall may add some); the layout is :mod:`icewall.analysis.baseline`'s docstring."""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from pathlib import Path

from icewall.deck.yamlsrc import LineDict, LineList, load_yaml, short_repr
from icewall.errors import DeckError, ResultError

Check = Callable[[object], str | None]  # value -> what is wrong with it (None: fine)


def _number(value) -> str | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return f"expected a number, got {short_repr(value)}"
    try:
        if not math.isfinite(float(value)):
            return f"{value} is not a finite number"
    except OverflowError:
        return f"{short_repr(value, 20)} is too large for a number"
    return None


def _string(value) -> str | None:
    return None if isinstance(value, str) else f"expected a string, got {short_repr(value)}"


def _boolean(value) -> str | None:
    return None if isinstance(value, bool) else f"expected true or false, got {short_repr(value)}"


def _integer(value) -> str | None:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        return f"expected a whole number >= 0, got {short_repr(value)}"
    return None


def _optional(check: Check) -> Check:
    return lambda value: None if value is None else check(value)


def _list_of(check: Check, length: int | None = None) -> Check:
    def checked(value) -> str | None:
        if not isinstance(value, list):
            return f"expected a list, got {short_repr(value)}"
        if length is not None and len(value) != length:
            return f"expected a list of {length}, got {short_repr(value)}"
        return next((f"item {i}: {why}" for i, v in enumerate(value)
                     if (why := check(v)) is not None), None)
    return checked


_BAND = _optional(_list_of(_number, 2))
RUN_KEYS: dict[str, Check] = {
    "specimen": _optional(_string), "deck": _optional(_string),
    "overrides": _optional(_list_of(_string)), "status": _string,
    "stop_reason": _optional(_string), "unit": _optional(_string),
    "peak_load": _optional(_number), "deflection_at_peak": _optional(_number),
    "peaked": _optional(_boolean), "final_deflection": _optional(_number),
    "residual_deflection": _optional(_number), "residual_load": _optional(_number),
    "curve_deflections": _optional(_list_of(_number)),
    "curve_loads": _optional(_list_of(_optional(_number))),
    "realizations": _optional(_integer), "statuses": _optional(_list_of(_string)),
    "peak_band": _BAND, "residual_band": _BAND, "curve_bands": _optional(_list_of(_BAND)),
}
TOLERANCE_KEYS: dict[str, Check] = {
    "peak": _optional(_number), "curve": _optional(_number), "residual": _optional(_number),
    "ratio_band": _optional(_list_of(_number, 2)),
}
RATIO_KEYS: dict[str, Check] = {"name": _optional(_string), "mean": _optional(_number),
                                "n": _optional(_integer)}


def _line(node, key) -> int | None:
    """The line of `key` in a parsed mapping (LineDict) or list (LineList), where known."""
    return node.line_of(key) if isinstance(node, LineDict | LineList) else None


def _check_mapping(data: dict, keys: dict[str, Check], where: str, file: str) -> None:
    for key, check in keys.items():
        if key in data and (why := check(data[key])) is not None:
            raise DeckError(why, file, _line(data, key), f"{where}.{key}" if where else key)


def _mapping(data: dict, key: str, file: str, where: str = "") -> dict:
    value = data.get(key)
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise DeckError(f"expected a mapping, got {short_repr(value)}", file,
                        _line(data, key), f"{where}.{key}" if where else key)
    return value


def check_baseline(data: object, file: str) -> dict:
    """`data` (a parsed baseline) checked; DeckError naming file, line and key otherwise."""
    if not isinstance(data, dict) or not isinstance(data.get("runs"), dict):
        raise DeckError("not a baseline file (no 'runs' mapping)", file,
                        getattr(data, "line", None))
    _check_mapping(_mapping(data, "tolerances", file), TOLERANCE_KEYS, "tolerances", file)
    _check_mapping(_mapping(data, "ratio", file), RATIO_KEYS, "ratio", file)
    band = _mapping(data, "tolerances", file).get("ratio_band")
    if band is not None and band[0] > band[1]:
        raise DeckError(f"the band {band} has LO > HI", file,
                        _line(data["tolerances"], "ratio_band"), "tolerances.ratio_band")
    for name, run in data["runs"].items():
        if not isinstance(run, dict):
            raise DeckError(f"expected a mapping, got {short_repr(run)}", file,
                            _line(data["runs"], name), f"runs.{name}")
        _check_mapping(run, RUN_KEYS, f"runs.{name}", file)
    return data


def read_baseline(path: str | os.PathLike) -> dict:
    """Read and check a baseline file: ResultError if it is missing or unreadable, DeckError
    (file, line, key) if it is malformed; both one line, exit 2."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise ResultError(f"cannot read the baseline {path}: {exc.strerror} "
                          "(write one with --update)") from None
    except UnicodeDecodeError as exc:
        raise DeckError(f"not a text file (byte {exc.start} is not UTF-8)", os.fspath(path)
                        ) from None
    if "\x00" in text:
        raise DeckError("the baseline holds a NUL byte (not a text file?)", os.fspath(path),
                        text.count("\n", 0, text.index("\x00")) + 1)
    return check_baseline(load_yaml(text, os.fspath(path)), os.fspath(path))
