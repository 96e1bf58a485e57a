"""Load a deck: read YAML (with lines), apply --set overrides, build dataclasses, validate."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from icewall.deck.fields import Context, build
from icewall.deck.profile import Profile, attribute_error, load_profile
from icewall.deck.schema import Deck
from icewall.deck.validate import validate
from icewall.deck.yamlsrc import LineDict, LineList, load_yaml, parse_yaml, read_yaml, short_repr
from icewall.errors import DeckError

_PATH_TOKEN = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)(?:\[(\d+)\])?")


@dataclass(frozen=True)
class LoadedDeck:
    """A validated deck with its source text and parsed tree (for line look-ups)."""

    deck: Deck
    text: str
    path: str
    tree: LineDict
    overrides: tuple[str, ...] = ()  # the profile's assignments, then --set, on `text`
    profile: Profile | None = None  # the profile applied under --set (deck.profile)

    def line_of(self, key_path: str) -> int | None:
        return line_of(self.tree, key_path)


def line_of(tree: LineDict, key_path: str) -> int | None:
    """Line of a dotted key path such as 'geometry.diaphragms.positions[2]' (best effort)."""
    node, line = tree, tree.line
    for token in key_path.split("."):
        match = _PATH_TOKEN.fullmatch(token)
        if match is None or not isinstance(node, dict) or match.group(1) not in node:
            return line
        key, index = match.group(1), match.group(2)
        line = node.line_of(key) if isinstance(node, LineDict) else line
        node = node[key]
        if index is not None and isinstance(node, list) and int(index) < len(node):
            line = node.line_of(int(index)) if isinstance(node, LineList) else line
            node = node[int(index)]
    return line


def apply_override(tree: LineDict, assignment: str, file: str) -> None:
    """Apply one `key.path=value` override (value parsed as YAML) in place."""
    if "=" not in assignment:
        raise DeckError(f"--set expects key.path=value, got {assignment!r}", file)
    key_path, raw = assignment.split("=", 1)
    keys = key_path.strip().split(".")
    if not all(_PATH_TOKEN.fullmatch(k) and "[" not in k for k in keys):
        raise DeckError(f"--set: bad key path {key_path!r}", file)
    try:
        value = load_yaml(raw, "--set")
    except DeckError as exc:
        raise DeckError(f"--set {key_path}: cannot parse value {short_repr(raw)}: {exc.detail}",
                        file) from None
    node = tree
    for key in keys[:-1]:
        child = node.get(key)
        if child is None:
            child = LineDict()
            child.line, child.key_lines = None, {}
            node[key] = child
        if not isinstance(child, dict):
            raise DeckError(f"--set {key_path}: {key!r} is not a mapping", file)
        node = child
    node[keys[-1]] = value
    if isinstance(node, LineDict):
        node.key_lines[keys[-1]] = None


def load_deck(path: str | Path, overrides: tuple[str, ...] | list[str] = (),
              profile: str | Profile | None = None) -> LoadedDeck:
    """Read, override, build and validate a deck file; `profile` (a name, a path or a loaded
    Profile) is applied under the overrides (deck.profile). Raises DeckError on any problem."""
    text, tree = read_yaml(path)
    return _finish(text, tree, str(path), overrides, load_profile(profile))


def load_deck_text(text: str, name: str = "<deck>",
                   overrides: tuple[str, ...] | list[str] = (),
                   profile: str | Profile | None = None) -> LoadedDeck:
    """Same as load_deck for deck text held in memory (tests, results files)."""
    return _finish(text, parse_yaml(text, name), name, overrides, load_profile(profile))


def _specimen_key(tree: LineDict, key: str) -> str | None:
    specimen = tree.get("specimen")
    value = specimen.get(key) if isinstance(specimen, dict) else None
    return value if isinstance(value, str) else None


def _finish(text: str, tree: LineDict, file: str, overrides, profile: Profile | None
            ) -> LoadedDeck:
    user = list(overrides)
    assignments = ([] if profile is None else
                   profile.assignments(_specimen_key(tree, "name"), _specimen_key(tree, "series")))
    user_keys = [o.split("=", 1)[0].strip() for o in user]
    try:
        for item in assignments:
            apply_override(tree, item.text, profile.path if profile else file)
        for assignment in user:
            apply_override(tree, assignment, file)
        deck = build(Deck, tree, Context(file))
        loaded = LoadedDeck(deck=deck, text=text, path=file, tree=tree,
                            overrides=tuple(item.text for item in assignments) + tuple(user),
                            profile=profile)
        validate(loaded.deck,
                 lambda message, key: DeckError(message, file, loaded.line_of(key), key))
    except DeckError as exc:
        if profile is None:
            raise
        raise attribute_error(exc, assignments, profile, user_keys) from None
    return loaded
