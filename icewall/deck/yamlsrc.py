"""YAML reading that keeps line numbers and refuses duplicate keys.

Mappings load as `LineDict` (a dict that also knows the line of each key and of itself) and
sequences as `LineList`, so every validation error can name the file and line.
"""

from __future__ import annotations

from pathlib import Path

import yaml

from icewall.errors import DeckError


class LineDict(dict):
    """A dict with `.line` (1-based line of the mapping) and `.key_lines` (key -> line)."""

    line: int | None = None
    key_lines: dict

    def line_of(self, key: str) -> int | None:
        return self.key_lines.get(key, self.line) if hasattr(self, "key_lines") else self.line


class LineList(list):
    """A list with `.line` and `.item_lines` (index -> line)."""

    line: int | None = None
    item_lines: list

    def line_of(self, index: int) -> int | None:
        lines = getattr(self, "item_lines", [])
        return lines[index] if index < len(lines) else self.line


def _make_loader(file: str) -> type[yaml.SafeLoader]:
    class _Loader(yaml.SafeLoader):
        pass

    def construct_mapping(loader: yaml.SafeLoader, node: yaml.MappingNode) -> LineDict:
        out = LineDict()
        out.line = node.start_mark.line + 1
        out.key_lines = {}
        for key_node, value_node in node.value:
            key = loader.construct_object(key_node, deep=True)
            line = key_node.start_mark.line + 1
            if not isinstance(key, str):
                raise DeckError(f"keys must be strings, got {key!r}", file, line)
            if key in out:
                raise DeckError(f"duplicate key (first given on line {out.key_lines[key]})",
                                file, line, key)
            out[key] = loader.construct_object(value_node, deep=True)
            out.key_lines[key] = line
        return out

    def construct_sequence(loader: yaml.SafeLoader, node: yaml.SequenceNode) -> LineList:
        out = LineList(loader.construct_object(child, deep=True) for child in node.value)
        out.line = node.start_mark.line + 1
        out.item_lines = [child.start_mark.line + 1 for child in node.value]
        return out

    _Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, construct_mapping)
    _Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_SEQUENCE_TAG, construct_sequence)
    return _Loader


def parse_yaml(text: str, file: str = "<deck>") -> LineDict:
    """Parse deck text into a LineDict; syntax errors become DeckError with the line."""
    try:
        data = yaml.load(text, Loader=_make_loader(file))  # noqa: S506 - SafeLoader subclass
    except DeckError:
        raise
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark is not None else None
        problem = exc.problem or str(exc)
        raise DeckError(f"YAML syntax error: {problem}", file, line) from None
    except yaml.YAMLError as exc:
        raise DeckError(f"YAML error: {exc}", file) from None
    if data is None:
        raise DeckError("the deck is empty", file, 1)
    if not isinstance(data, LineDict):
        raise DeckError("the deck must be a YAML mapping (key: value lines)", file, 1)
    return data


def read_yaml(path: str | Path) -> tuple[str, LineDict]:
    """Read and parse a deck file; returns (text, tree)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise DeckError("no such file", str(path)) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise DeckError(f"cannot read the deck: {exc}", str(path)) from None
    return text, parse_yaml(text, str(path))
