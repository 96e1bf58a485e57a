"""YAML reading that keeps line numbers and refuses duplicate keys.

Mappings load as `LineDict` (a dict that also knows the line of each key and of itself) and
sequences as `LineList`, so every validation error can name the file and line.
"""

from __future__ import annotations

import re
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


MAX_DEPTH = 64
"""Deepest nesting of mappings and lists a deck may have (the format needs 5 levels)."""

# YAML 1.2 floats with an exponent but no dot or no exponent sign (1e12, 1.0e12, 2E-3): YAML
# 1.1, which PyYAML implements, reads them as strings.
_EXPONENT_FLOAT = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$")
_MERGE_TAG = "tag:yaml.org,2002:merge"


def _make_loader(file: str) -> type[yaml.SafeLoader]:
    class _Loader(yaml.SafeLoader):
        pass

    _Loader.add_implicit_resolver("tag:yaml.org,2002:float", _EXPONENT_FLOAT,
                                  list("-+0123456789."))

    def construct_mapping(loader: yaml.SafeLoader, node: yaml.MappingNode) -> LineDict:
        out = LineDict()
        out.line = node.start_mark.line + 1
        out.key_lines = {}
        n_own = sum(key_node.tag != _MERGE_TAG for key_node, _ in node.value)
        loader.flatten_mapping(node)  # merge keys (<<: *anchor): merged entries come first
        n_merged = len(node.value) - n_own
        own: set[str] = set()
        for i, (key_node, value_node) in enumerate(node.value):
            key = loader.construct_object(key_node, deep=True)
            line = key_node.start_mark.line + 1
            if not isinstance(key, str):
                raise DeckError(f"keys must be strings, got {short_repr(key)}", file, line)
            if i >= n_merged:  # a key given here may override a merged one, not another here
                if key in own:
                    raise DeckError(f"duplicate key (first given on line {out.key_lines[key]})",
                                    file, line, key)
                own.add(key)
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


def short_repr(value: object, limit: int = 60) -> str:
    """repr of `value`, cut to `limit` characters (messages stay one line)."""
    try:
        text = repr(value)
    except (RecursionError, ValueError):  # nested too deep; an int of 4300+ digits
        text = f"<a {type(value).__name__} too large to show>"
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _nesting_error(text: str, file: str) -> DeckError:
    """Line of the first mapping or list opened deeper than MAX_DEPTH (scanned without
    recursion: the parser's own recursion is what overflowed)."""
    line = None
    try:
        depth = 0
        for event in yaml.parse(text, Loader=yaml.SafeLoader):
            if isinstance(event, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
                depth += 1
                if depth > MAX_DEPTH:
                    line = event.start_mark.line + 1
                    break
            elif isinstance(event, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
                depth -= 1
    except yaml.YAMLError:
        pass
    return DeckError(f"mappings and lists nested more than {MAX_DEPTH} deep", file, line)


def _depth_exceeds(node: yaml.Node, limit: int) -> bool:
    """Whether the composed node tree is deeper than `limit` (iterative)."""
    stack = [(node, 1)]
    seen: set[int] = set()
    while stack:
        current, depth = stack.pop()
        if depth > limit:
            return True
        if id(current) in seen or not isinstance(current, (yaml.MappingNode,
                                                           yaml.SequenceNode)):
            continue
        seen.add(id(current))
        children = (current.value if isinstance(current, yaml.SequenceNode)
                    else [v for pair in current.value for v in pair])
        stack.extend((child, depth + 1) for child in children)
    return False


def _control_character_error(text: str, exc: yaml.reader.ReaderError, file: str
                              ) -> DeckError:
    """A character YAML does not allow (a control character, a lone surrogate), where it is."""
    position = exc.position if isinstance(exc.position, int) else 0
    line = text.count("\n", 0, position) + 1
    column = position - (text.rfind("\n", 0, position) + 1) + 1
    code = exc.character if isinstance(exc.character, int) else ord(text[position])
    return DeckError(f"character U+{code:04X} at column {column} is not allowed in YAML (a "
                     "control character; not a text file?)", file, line)


def load_yaml(text: str, file: str = "<deck>") -> object:
    """Parse YAML text with the deck loader (lines kept, YAML 1.2 exponent floats, merge
    keys, no duplicate keys, at most MAX_DEPTH deep); any problem is a one-line DeckError."""
    try:  # the reader refuses control characters as it is made
        loader = _make_loader(file)(text)
    except yaml.reader.ReaderError as exc:
        raise _control_character_error(text, exc, file) from None
    try:
        node = loader.get_single_node()
        if node is not None and _depth_exceeds(node, MAX_DEPTH):
            raise _nesting_error(text, file)
        return None if node is None else loader.construct_document(node)
    except DeckError:
        raise
    except RecursionError:
        raise _nesting_error(text, file) from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark is not None else None
        problem = exc.problem or str(exc)
        raise DeckError(f"YAML syntax error: {problem}", file, line) from None
    except yaml.YAMLError as exc:
        raise DeckError(f"YAML error: {' '.join(str(exc).split())}", file) from None
    except ValueError as exc:  # e.g. an integer of more than 4300 digits
        raise DeckError(f"cannot read a value ({str(exc).split(';')[0]})", file) from None
    finally:
        loader.dispose()


def parse_yaml(text: str, file: str = "<deck>") -> LineDict:
    """Parse deck text into a LineDict; syntax errors become DeckError with the line."""
    if "\x00" in text:
        line = text.count("\n", 0, text.index("\x00")) + 1
        raise DeckError("the deck holds a NUL byte (not a text file?)", file, line)
    data = load_yaml(text, file)
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
