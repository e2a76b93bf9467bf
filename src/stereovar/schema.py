"""JSON-Schema helpers shared by the workflow config (:mod:`stereovar.config`) and the scene
specs (:mod:`stereovar.scenes.spec`): plain data, YAML loading and default filling."""

from __future__ import annotations

import copy
import os
from collections.abc import Mapping
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


def load_yaml(path, what: str, *, error: type[StereovarError] = ConfigError):
    """Parse a YAML file; a missing, unreadable or invalid file is one ``error`` line."""
    import yaml

    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise error(f"{what} '{path}' does not exist") from None
    except OSError as err:
        raise error(f"{what} '{path}' cannot be read: {err.strerror}") from None
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(err, "problem", None) or "syntax error"
        raise error(f"{what} '{path}' is not valid YAML{where}: {problem}") from None


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
