"""Deck profiles: named overlays of deck values applied under `--set` (`--profile NAME`).

A profile is a YAML file (`decks/profiles/NAME.yaml`, or any path) with the keys

    profile: NAME          # its name (default: the file's stem)
    description: text
    overlay: {...}         # deck values for every deck (a partial deck tree)
    series: {CF: {...}}    # and for the decks of one series (specimen.series)
    specimens: {CF-4: {...}}  # and for one specimen (specimen.name)

merged in that order onto the deck, each later one winning, and `--set` over all of them.
The overlay is flattened into `key.path=value` assignments (a mapping is merged key by key, a
list or scalar replaces the deck's) put before the `--set` ones, so a result's stored
overrides (`deck_overrides`) rebuild the deck the run saw; the profile's name and text are
stored beside them (pipeline). An error in a value the profile set names the profile's file
and line.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path

from icewall.deck.yamlsrc import LineDict, read_yaml
from icewall.errors import DeckError

PROFILE_KEYS = ("profile", "description", "overlay", "series", "specimens")
PROFILE_DIRECTORY = Path("decks") / "profiles"
"""Where a profile NAME is looked up: under the working directory, then the source tree's."""


@dataclass(frozen=True)
class Assignment:
    """One `key.path=value` of a profile, with the line it came from."""

    key: str
    value: str  # YAML (JSON) text of the value
    line: int | None

    @property
    def text(self) -> str:
        return f"{self.key}={self.value}"


@dataclass(frozen=True)
class Profile:
    """A loaded profile: name, file, text and parsed tree."""

    name: str
    path: str
    text: str
    tree: LineDict = field(repr=False)

    @property
    def sha256(self) -> str:
        return hashlib.sha256(self.text.encode()).hexdigest()

    def assignments(self, specimen: str | None, series: str | None) -> list[Assignment]:
        """The flattened overlay for a deck of this specimen and series (overlay, then its
        series' section, then its specimen's)."""
        out: list[Assignment] = []
        sections = [(self.tree.get("overlay"), "overlay")]
        for key, wanted in (("series", series), ("specimens", specimen)):
            table = self.tree.get(key) or {}
            if wanted is not None and wanted in table:
                sections.append((table[wanted], f"{key}.{wanted}"))
        for section, where in sections:
            if section is not None:
                _flatten(section, "", out, self.path, where)
        return out


def _plain(value: object) -> object:
    """A LineDict/LineList tree as plain dicts and lists (for JSON)."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_plain(v) for v in value]
    return value


def _flatten(node: object, prefix: str, out: list[Assignment], file: str, where: str) -> None:
    if not isinstance(node, dict):
        raise DeckError(f"{where}: expected a mapping of deck keys", file,
                        getattr(node, "line", None))
    for key, value in node.items():
        path = f"{prefix}{key}"
        line = node.line_of(key) if isinstance(node, LineDict) else None
        if isinstance(value, dict) and value:
            _flatten(value, path + ".", out, file, where)
        else:
            out.append(Assignment(path, json.dumps(_plain(value)), line))


def find_profile(spec: str) -> Path:
    """The file of profile `spec`: a path to a YAML file, or a name looked up as
    decks/profiles/NAME.yaml under the working directory, then under the source tree."""
    given = Path(spec)
    if given.suffix in (".yaml", ".yml") or given.parent != Path("."):
        if given.is_file():
            return given
        raise DeckError(f"no profile file {spec}", "--profile")
    places = [Path.cwd() / PROFILE_DIRECTORY, Path(__file__).resolve().parents[2]
              / PROFILE_DIRECTORY]
    for place in places:
        for suffix in (".yaml", ".yml"):
            if (place / f"{spec}{suffix}").is_file():
                return place / f"{spec}{suffix}"
    known = sorted({p.stem for place in places if place.is_dir()
                    for p in place.glob("*.y*ml")})
    raise DeckError(f"unknown profile {spec!r} (known: {', '.join(known) or 'none'}; or give "
                    "a path to a profile file)", "--profile")


def load_profile(spec: str | Profile | None) -> Profile | None:
    """Read and check a profile given by name or path (None: no profile)."""
    if spec is None or isinstance(spec, Profile):
        return spec
    path = find_profile(str(spec))
    text, tree = read_yaml(path)
    file = str(path)
    if not isinstance(tree, dict):
        raise DeckError("a profile is a mapping of profile, description, overlay, series, "
                        "specimens", file)
    for key in tree:
        if key not in PROFILE_KEYS:
            raise DeckError(f"unknown key (allowed here: {', '.join(PROFILE_KEYS)})", file,
                            tree.line_of(key), str(key))
    for key in ("series", "specimens"):
        table = tree.get(key)
        if table is not None and not isinstance(table, dict):
            raise DeckError("expected a mapping of names to deck overlays", file,
                            tree.line_of(key), key)
    name = tree.get("profile") or path.stem
    if not isinstance(name, str):
        raise DeckError("expected a string", file, tree.line_of("profile"), "profile")
    profile = Profile(name=name, path=file, text=text, tree=tree)
    for table_key in ("series", "specimens"):  # every section flattens (values checked later)
        for wanted in tree.get(table_key) or {}:
            _flatten(tree[table_key][wanted], "", [], file, f"{table_key}.{wanted}")
    if tree.get("overlay") is not None:
        _flatten(tree["overlay"], "", [], file, "overlay")
    return profile


def attribute_error(exc: DeckError, assignments: list[Assignment], profile: Profile,
                    user_keys: list[str]) -> DeckError:
    """`exc` re-addressed to the profile's file and line where its key is one the profile set
    (and no --set replaced); else `exc` itself."""
    if exc.key is None:
        return exc
    for item in reversed(assignments):
        key = item.key
        hit = exc.key == key or exc.key.startswith((key + ".", key + "["))
        replaced = any(u == key or u.startswith(key + ".") or key.startswith(u + ".")
                       for u in user_keys)
        if hit and not replaced:
            return DeckError(f"{exc.detail} (set by profile {profile.name})", profile.path,
                             item.line, exc.key)
    return exc
