"""JSON-Schema helpers shared by the workflow config (:mod:`stereovar.config`) and the scene
specs (:mod:`stereovar.scenes.spec`): plain data, YAML loading and default filling."""

from __future__ import annotations

import copy
import os
import re
from collections.abc import Mapping
from functools import lru_cache
from pathlib import Path

from .errors import ConfigError, StereovarError


def plain(value, *, ndigits: int | None = None, strict: bool = False):
    """Deep copy as plain Python: mappings as dict (string keys), sequences as list.

    Numpy scalars and arrays become Python numbers and lists; floats are optionally rounded
    to ``ndigits`` and ``-0.0`` becomes ``0.0``; path-likes become strings.

    Parameters
    ----------
    value : object
    ndigits : int, keyword-only, optional
        Round floats to this many decimals.
    strict : bool, keyword-only
        Raise ``TypeError`` for any other type (instead of deep-copying it).
    """
    if isinstance(value, Mapping):
        return {str(k): plain(v, ndigits=ndigits, strict=strict) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [plain(v, ndigits=ndigits, strict=strict) for v in value]
    if hasattr(value, "tolist") and not isinstance(value, str | bytes):
        return plain(value.tolist(), ndigits=ndigits, strict=strict)
    if isinstance(value, bool) or value is None or isinstance(value, int | str):
        return value
    if isinstance(value, float):
        if ndigits is not None:
            value = round(value, ndigits)
        return 0.0 if value == 0 else value
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if strict:
        raise TypeError(f"cannot serialise {type(value).__name__}")
    return copy.deepcopy(value)


MAX_YAML_VALUES = 100_000
"""Most values (scalars, lists and mappings, counted with every YAML alias expanded) that a
config, an audit config or a scene spec may hold. The largest shipped file holds a few
hundred; a "billion laughs" file of nested aliases holds billions, which copying, validating
or hashing would expand in memory."""


def expanded_size(value) -> int:
    """Number of values in ``value`` with every shared reference expanded, counted without
    expanding anything.

    A mapping counts as one value plus its keys and values, a list as one plus its items,
    anything else as one. Each distinct list or mapping is counted once and its count reused
    wherever it is referenced again, so the cost is that of the distinct objects (what YAML
    aliases load to), not of the expanded tree.

    Raises
    ------
    ValueError
        When a list or mapping contains itself (a recursive YAML alias).
    """
    sizes: dict[int, int] = {}
    open_ids: set[int] = set()

    def size(node) -> int:
        if isinstance(node, Mapping):
            children = [c for item in node.items() for c in item]
        elif isinstance(node, list | tuple):
            children = list(node)
        else:
            return 1
        key = id(node)
        if key in sizes:
            return sizes[key]
        if key in open_ids:
            raise ValueError("a list or mapping contains itself")
        open_ids.add(key)
        total = 1 + sum(size(c) for c in children)
        open_ids.discard(key)
        sizes[key] = total
        return total

    return size(value)


def _yaml_size(node, sizes: dict) -> int:
    """:func:`expanded_size` of a composed YAML node (an alias is the node it names)."""
    key = id(node)
    if key not in sizes:
        value = node.value
        if isinstance(value, list):
            pairs = (c for item in value for c in (item if isinstance(item, tuple) else (item,)))
            sizes[key] = 1 + sum(_yaml_size(c, sizes) for c in pairs)
        else:
            sizes[key] = 1
    return sizes[key]


@lru_cache(maxsize=1)
def _bounded_loader():
    """``yaml.SafeLoader`` that counts the values of the document as it composes it, aliases
    expanded, and stops at the first node past ``limit`` (a recursive alias at once)."""
    import yaml
    from yaml.composer import ComposerError
    from yaml.events import AliasEvent, CollectionStartEvent

    class BoundedSafeLoader(yaml.SafeLoader):
        limit = MAX_YAML_VALUES

        def __init__(self, stream):
            super().__init__(stream)
            self._values = 0
            self._sizes: dict = {}
            self._open: set = set()

        def compose_node(self, parent, index):
            event = self.peek_event()
            if isinstance(event, AliasEvent) and event.anchor in self._open:
                raise ComposerError(
                    None,
                    None,
                    f"alias *{event.anchor} refers to the list or mapping that contains "
                    "it; a document cannot contain itself",
                    event.start_mark,
                )
            anchor = event.anchor if isinstance(event, CollectionStartEvent) else None
            if anchor is not None:
                self._open.add(anchor)
            try:
                node = super().compose_node(parent, index)
            finally:
                self._open.discard(anchor)
            # a node composed here counts itself (its children counted themselves); an
            # alias counts everything it repeats
            added = _yaml_size(node, self._sizes) if isinstance(event, AliasEvent) else 1
            self._values += added
            if self._values > self.limit:
                raise ComposerError(
                    None,
                    None,
                    f"the aliases up to here expand the document to more than "
                    f"{self.limit:,} values; write the values out or repeat fewer aliases",
                    event.start_mark,
                )
            return node

    return BoundedSafeLoader


def parse_yaml(text: str, *, name: str | None = None):
    """``yaml.safe_load`` that refuses a document of more than :data:`MAX_YAML_VALUES`
    values, YAML aliases expanded, and a recursive alias, before building anything.

    Aliases load as shared references (as with ``yaml.safe_load``), so the result is as
    small as the text; the bound keeps every later deep copy, validation or hash of it
    small too.

    Parameters
    ----------
    text : str
        The YAML document.
    name : str, keyword-only, optional
        The file's name, shown in the error's position (``in "<name>", line L``).

    Raises
    ------
    yaml.YAMLError
        A ``MarkedYAMLError`` whose ``problem`` says what is wrong and ``problem_mark`` where:
        a syntax error, a tag that builds a Python object, or the bounds above.
    """
    import io

    stream = io.StringIO(text)
    if name is not None:
        stream.name = name
    loader = _bounded_loader()(stream)
    try:
        return loader.get_single_data()
    finally:
        loader.dispose()


def yaml_problem(err) -> str:
    """The problem of a ``yaml.YAMLError`` in words, on one line; a tag that would build a
    Python object (``!!python/object:...``) is named as written, with the fix."""
    problem = getattr(err, "problem", None) or "syntax error"
    tag = re.search(r"the tag '(tag:yaml\.org,2002:|!)(python/[^']*)'", str(problem))
    if tag:
        bangs = "!" if tag.group(1) == "!" else "!!"
        return (
            f"the tag {bangs}{tag.group(2)} would build a Python object, which is never read; "
            "remove the tag and give the plain value"
        )
    return " ".join(str(problem).split())


def load_yaml(path, what: str, *, error: type[StereovarError] = ConfigError):
    """Parse a YAML file (:func:`parse_yaml`); a missing, unreadable or invalid file, a tag
    that builds a Python object, or aliases that expand past :data:`MAX_YAML_VALUES` values
    are one ``error`` line naming the file and the line."""
    import yaml

    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise error(f"{what} '{path}' does not exist") from None
    except (OSError, UnicodeDecodeError) as err:
        why = getattr(err, "strerror", None) or str(err)
        raise error(f"{what} '{path}' cannot be read: {why}") from None
    try:
        return parse_yaml(text, name=str(path))
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise error(f"{what} '{path}' is not valid YAML{where}: {yaml_problem(err)}") from None


def resolve(schema, root: Mapping):
    """Follow local ``$ref`` pointers (``#/$defs/...``) of ``root``."""
    seen = 0
    while isinstance(schema, dict) and "$ref" in schema:
        ref = schema["$ref"]
        if not ref.startswith("#/"):
            raise ValueError(f"only local $ref is supported, got {ref!r}")
        node = root
        for part in ref[2:].split("/"):
            node = node[part]
        schema = node
        seen += 1
        if seen > 32:
            raise ValueError("cyclic $ref in the schema")
    return schema


def with_defs(sub, root: Mapping):
    """A sub-schema that can resolve the root's ``$defs`` when validated on its own."""
    if isinstance(sub, dict) and "$defs" not in sub and "$defs" in root:
        return {**sub, "$defs": root["$defs"]}
    return sub


def fill_defaults(instance, schema, *, root: Mapping | None = None) -> None:
    """Insert the schema's ``default`` values into a *valid* instance, in place.

    Walks ``properties``, ``additionalProperties``, ``items`` and ``allOf``; for ``oneOf`` and
    ``anyOf`` only the first branch that the instance satisfies is followed, so defaults of
    other branches never leak in. A default next to a ``$ref`` wins over one inside the
    referenced schema.

    Parameters
    ----------
    instance : dict or list
    schema : dict
        The (sub-)schema ``instance`` was validated against.
    root : mapping, keyword-only, optional
        The root schema that ``$ref`` pointers resolve in (``schema`` itself by default).
    """
    root = schema if root is None else root
    schema = resolve(schema, root)
    if not isinstance(schema, dict):
        return
    if isinstance(instance, dict):
        props = schema.get("properties", {})
        for key, sub in props.items():
            if key in instance:
                continue
            for candidate in (sub, resolve(sub, root)):
                if isinstance(candidate, dict) and "default" in candidate:
                    instance[key] = copy.deepcopy(candidate["default"])
                    break
        for key, value in instance.items():
            if key in props:
                fill_defaults(value, props[key], root=root)
            elif isinstance(schema.get("additionalProperties"), dict):
                fill_defaults(value, schema["additionalProperties"], root=root)
    if isinstance(instance, list) and isinstance(schema.get("items"), dict):
        for item in instance:
            fill_defaults(item, schema["items"], root=root)
    for sub in schema.get("allOf", []):
        fill_defaults(instance, sub, root=root)
    for keyword in ("oneOf", "anyOf"):
        branches = schema.get(keyword, [])
        if not branches:
            continue
        import jsonschema

        cls = jsonschema.validators.validator_for(root)
        for sub in branches:
            if cls(with_defs(sub, root)).is_valid(instance):
                fill_defaults(instance, sub, root=root)
                break
