"""Load, validate, digest and write renderer-neutral scene specs.

The format is defined by ``schemas/scene.schema.yaml``. :func:`load_scene_spec` validates a
file against it with :mod:`jsonschema`, fills the schema's defaults, and checks what a schema
cannot express (cross references, the file name, shape-specific rules). Every problem is
reported as a :class:`~stereovar.errors.SceneError` whose message is one line naming the file
and the dotted key, e.g. ::

    scenes/kitchen.yaml: objects.3.shape: 'cube' is not allowed; use one of rectangle, box, ...
"""

from __future__ import annotations

import copy
import hashlib
import json
import os
import tempfile
from functools import lru_cache
from pathlib import Path

from ..errors import SceneError
from ..schema import fill_defaults, parse_yaml, plain, resolve, yaml_problem
from .references import xml_references

SCHEMA_PATH = Path(__file__).resolve().parents[1] / "schemas" / "scene.schema.yaml"

#: Keys of a procedural scene that must be absent when ``mitsuba_xml`` is set.
PROCEDURAL_KEYS = ("camera", "textures", "materials", "objects", "lights")

#: Preferred key order when writing specs; other keys follow alphabetically.
_KEY_ORDER = (
    "name",
    "description",
    "generator",
    "mitsuba_xml",
    "camera",
    "textures",
    "materials",
    "objects",
    "lights",
    "origin",
    "target",
    "up",
    "fov_deg",
    "shape",
    "type",
    "pattern",
    "material",
    "texture",
    "metal",
    "colors",
    "reflectance",
    "radiance",
    "roughness",
    "ior",
    "tint",
    "repeat",
    "seed",
    "index",
    "version",
    "resolution",
    "profile",
    "segments",
    "transform",
    "translate",
    "rotate",
    "scale",
)
_KEY_RANK = {k: i for i, k in enumerate(_KEY_ORDER)}


# --------------------------------------------------------------------------------------------
# schema handling
# --------------------------------------------------------------------------------------------


@lru_cache(maxsize=1)
def _schema() -> dict:
    import yaml

    with open(SCHEMA_PATH, encoding="utf-8") as fh:
        return yaml.safe_load(fh)


@lru_cache(maxsize=1)
def _validator():
    import jsonschema

    schema = _schema()
    cls = jsonschema.validators.validator_for(schema)
    return cls(schema)


def _resolve(schema):
    """Follow local ``$ref`` pointers of the scene schema."""
    return resolve(schema, _schema())


def _dotted(path) -> str:
    return ".".join(str(p) for p in path) if len(path) else "(top level)"


def _short(value, limit: int = 60) -> str:
    text = json.dumps(value, default=str) if not isinstance(value, str) else repr(value)
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _branch_const(branch: dict, key: str = "type"):
    branch = _resolve(branch)
    prop = branch.get("properties", {}).get(key) if isinstance(branch, dict) else None
    prop = _resolve(prop) if prop is not None else None
    return prop.get("const") if isinstance(prop, dict) else None


def _describe(error) -> tuple[str, str]:
    """Turn a jsonschema error into ``(dotted key, one-line problem and fix)``."""
    path = list(error.absolute_path)
    instance = error.instance
    schema = error.schema if isinstance(error.schema, dict) else {}
    v = error.validator
    if v == "oneOf":
        return _describe_one_of(error, path)
    if v == "additionalProperties":
        allowed = sorted(schema.get("properties", {}))
        extra = sorted(set(instance) - set(allowed)) if isinstance(instance, dict) else []
        key = _dotted(path + extra[:1])
        return key, (
            f"unknown key {extra[0]!r}; allowed keys: {', '.join(allowed)}"
            if extra
            else error.message
        )
    if v == "required":
        missing = [k for k in error.validator_value if k not in instance]
        name = missing[0] if missing else "?"
        return _dotted(path + [name]), f"missing required key {name!r}"
    if v == "enum":
        allowed = ", ".join(str(x) for x in error.validator_value)
        return _dotted(path), f"{_short(instance)} is not allowed; use one of {allowed}"
    if v == "const":
        return _dotted(path), f"{_short(instance)} is not allowed; use {error.validator_value!r}"
    if v == "type":
        expected = error.validator_value
        expected = " or ".join(expected) if isinstance(expected, list) else expected
        return _dotted(path), f"expected {expected}, got {_short(instance)}"
    if v in ("minItems", "maxItems"):
        n = len(instance) if isinstance(instance, list) else "?"
        word = "at least" if v == "minItems" else "at most"
        return _dotted(path), f"needs {word} {error.validator_value} items, got {n}"
    if v in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"):
        rel = {
            "minimum": ">=",
            "maximum": "<=",
            "exclusiveMinimum": ">",
            "exclusiveMaximum": "<",
        }[v]
        return _dotted(path), f"{_short(instance)} must be {rel} {error.validator_value}"
    if v == "pattern":
        return _dotted(path), f"{_short(instance)} must match {error.validator_value!r}"
    return _dotted(path), " ".join(error.message.split())


def _describe_one_of(error, path) -> tuple[str, str]:
    import jsonschema

    instance = error.instance
    branches = error.validator_value
    key = _dotted(path)
    if not path:  # the top level: procedural scene versus mitsuba_xml
        if isinstance(instance, dict) and "mitsuba_xml" in instance:
            clash = [k for k in PROCEDURAL_KEYS if k in instance]
            return "mitsuba_xml", (
                f"a scene with mitsuba_xml must not set {', '.join(clash)}; remove them"
            )
        for k in ("camera", "materials", "objects", "lights"):
            if not isinstance(instance, dict) or k not in instance:
                return k, (
                    f"missing required key {k!r} (or give mitsuba_xml instead of a "
                    "procedural scene)"
                )
    # branches told apart by a `type` const (materials)
    consts = [_branch_const(b) for b in branches]
    if all(c is not None for c in consts) and isinstance(instance, dict):
        kind = instance.get("type")
        if kind not in consts:
            return _dotted(path + ["type"]), (
                f"{_short(kind)} is not allowed; use one of {', '.join(consts)}"
            )
        index = consts.index(kind)
        sub = [e for e in error.context if e.relative_schema_path[0] == index]
        if sub:
            best = jsonschema.exceptions.best_match(sub)
            return _describe(best)
    # branches that differ only in which key is required (exactly one of ...)
    reqs = [_resolve(b).get("required") for b in branches]
    pairs = zip(reqs, branches, strict=True)
    if all(r and len(r) == 1 and len(_resolve(b)) == 1 for r, b in pairs):
        names = [r[0] for r in reqs]
        return key, f"give exactly one of {', '.join(names)}"
    if error.context:
        return _describe(jsonschema.exceptions.best_match(error.context))
    return key, " ".join(error.message.split())


def validate_scene_dict(spec, *, source: str = "<scene>") -> dict:
    """Validate a scene dict against the schema and fill defaults (no file checks).

    Parameters
    ----------
    spec : dict
        A parsed scene spec; it is not modified.
    source : str
        Name used in error messages (usually the file path).

    Returns
    -------
    dict
        A deep copy with the schema's defaults filled in.

    Raises
    ------
    SceneError
        One line: ``"<source>: <dotted key>: <problem>"``.
    """
    if not isinstance(spec, dict):
        raise SceneError(f"{source}: (top level): expected a mapping of keys, got {_short(spec)}")
    errors = list(_validator().iter_errors(spec))
    if errors:
        # report errors inside keys before the structural top-level oneOf
        errors.sort(key=lambda e: len(e.absolute_path) == 0)
        key, problem = _describe(errors[0])
        raise SceneError(f"{source}: {key}: {problem}")
    out = copy.deepcopy(spec)
    if "mitsuba_xml" in out:
        # keep the procedural keys absent, as the schema requires for such scenes
        schema = {k: v for k, v in _schema().items() if k != "properties"}
        schema["properties"] = {
            k: v for k, v in _schema()["properties"].items() if k not in PROCEDURAL_KEYS
        }
        fill_defaults(out, schema, root=_schema())
    else:
        fill_defaults(out, _schema())
    return out


def _check_semantics(spec: dict, source: str, path: Path) -> None:
    """Cross references and rules the schema cannot express."""
    stem = path.stem
    if spec["name"] != stem:
        raise SceneError(
            f"{source}: name: {spec['name']!r} does not match the file name {stem!r}; "
            "rename the file or the scene"
        )
    if "mitsuba_xml" in spec:
        return
    textures = spec.get("textures", {})
    materials = spec.get("materials", {})
    for mname, mat in materials.items():
        tex = mat.get("texture")
        if mat["type"] in ("diffuse", "glossy") and tex is not None and tex not in textures:
            known = ", ".join(sorted(textures)) or "none"
            raise SceneError(
                f"{source}: materials.{mname}.texture: unknown texture {tex!r}; "
                f"defined textures: {known}"
            )
    seen: dict[str, str] = {}
    for i, obj in enumerate(spec.get("objects", [])):
        key = f"objects.{i}"
        if obj["name"] in seen:
            raise SceneError(
                f"{source}: {key}.name: duplicate name {obj['name']!r} (also {seen[obj['name']]})"
                "; names must be unique"
            )
        seen[obj["name"]] = key
        if obj["material"] not in materials:
            known = ", ".join(sorted(materials)) or "none"
            raise SceneError(
                f"{source}: {key}.material: unknown material {obj['material']!r} "
                f"(object {obj['name']!r}); defined materials: {known}"
            )
        shape = obj["shape"]
        if shape == "sphere":
            scale = obj.get("transform", {}).get("scale", [1.0, 1.0, 1.0])
            if max(scale) - min(scale) > 1e-9 * max(1.0, max(abs(s) for s in scale)):
                raise SceneError(
                    f"{source}: {key}.transform.scale: a sphere needs a uniform scale, got "
                    f"{_short(scale)} (object {obj['name']!r}); use equal factors"
                )
        if shape == "lathe":
            profile = obj.get("profile")
            if not profile or len(profile) < 2:
                raise SceneError(
                    f"{source}: {key}.profile: a lathe needs a profile of at least 2 [r, y] "
                    f"points (object {obj['name']!r})"
                )
            if any(p[0] < 0 for p in profile) or any(
                b[1] <= a[1] for a, b in zip(profile, profile[1:], strict=False)
            ):
                raise SceneError(
                    f"{source}: {key}.profile: radii must be >= 0 and heights must increase "
                    f"strictly from bottom to top (object {obj['name']!r})"
                )
    for i, light in enumerate(spec.get("lights", [])):
        key = f"lights.{i}"
        if light["name"] in seen:
            raise SceneError(
                f"{source}: {key}.name: duplicate name {light['name']!r} "
                f"(also {seen[light['name']]}); names must be unique"
            )
        seen[light["name"]] = key


def load_scene_spec(path) -> dict:
    """Read, validate and complete a scene spec file.

    Parameters
    ----------
    path : str or os.PathLike
        A YAML file following ``schemas/scene.schema.yaml``.

    Returns
    -------
    dict
        The spec with the schema's defaults filled in. For a scene that points at a Mitsuba
        XML file, ``mitsuba_xml`` holds the file's absolute path (resolved relative to the
        spec file's directory) and the procedural keys stay absent.

    Raises
    ------
    SceneError
        With a one-line message ``"<file>: <dotted key>: <problem>"`` for a missing file, a
        YAML syntax error, a tag that builds a Python object, YAML aliases that expand past
        :data:`~stereovar.schema.MAX_YAML_VALUES` values, a schema violation (for an enum,
        the allowed values; for an unknown key, the allowed keys), a ``name`` that differs
        from the file stem, an object referencing an unknown material, a diffuse or glossy
        material referencing an unknown texture, a sphere with non-uniform scale, a lathe
        without a profile of at least two points, duplicate object or light names, or a
        ``mitsuba_xml`` file that does not exist, is not well-formed XML or names a file
        that does not exist
        (:func:`~stereovar.scenes.references.xml_references`).
    """
    import yaml

    path = Path(path)
    source = str(path)
    if not path.is_file():
        raise SceneError(f"{source}: (file): scene spec not found; check the path")
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise SceneError(f"{source}: (file): cannot read: {err}") from None
    try:
        data = parse_yaml(text, name=source)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark is not None else "?"
        raise SceneError(f"{source}: (yaml): parse error at {where}: {yaml_problem(err)}") from None
    spec = validate_scene_dict(data, source=source)
    _check_semantics(spec, source, path)
    if "mitsuba_xml" in spec:
        xml = Path(spec["mitsuba_xml"]).expanduser()
        if not xml.is_absolute():
            xml = path.resolve().parent / xml
        xml = xml.resolve()
        if not xml.is_file():
            raise SceneError(
                f"{source}: mitsuba_xml: file {str(xml)!r} not found (paths are relative to "
                "the spec file's directory)"
            )
        spec["mitsuba_xml"] = str(xml)
        xml_references(xml)  # well-formed, and every file it names exists
    return spec


# --------------------------------------------------------------------------------------------
# digest and writing
# --------------------------------------------------------------------------------------------


def scene_spec_digest(spec: dict) -> str:
    """SHA-256 of a canonical JSON dump of a spec, for provenance.

    Parameters
    ----------
    spec : dict
        A scene spec, typically as returned by :func:`load_scene_spec` (defaults filled, so
        two files that differ only by spelled-out defaults get the same digest).

    Returns
    -------
    str
        64 hexadecimal characters. The dump sorts keys, uses compact separators and plain
        Python numbers. For a ``mitsuba_xml`` scene the path is replaced by the SHA-256 of
        the XML file's bytes when the file exists, so the digest follows the content and not
        the machine-specific location.
    """
    data = plain(spec, strict=True)
    xml = data.get("mitsuba_xml") if isinstance(data, dict) else None
    if xml and Path(xml).is_file():
        data["mitsuba_xml"] = "sha256:" + hashlib.sha256(Path(xml).read_bytes()).hexdigest()
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


_NAMED_MAPS = ("textures", "materials")


def scene_digest(spec: dict) -> str:
    """SHA-256 of a scene: its canonical spec plus, for XML scenes, the bytes of the file and
    of every file it reads (:func:`~stereovar.scenes.references.xml_references`), each with
    its path relative to the XML file's directory."""
    h = hashlib.sha256(scene_spec_digest(spec).encode())
    if "mitsuba_xml" in spec:
        xml = Path(spec["mitsuba_xml"])
        h.update(xml.read_bytes())
        for ref in xml_references(xml):
            h.update(os.path.relpath(ref, xml.parent).encode())
            h.update(hashlib.sha256(ref.read_bytes()).digest())
    return h.hexdigest()


def _ordered(value, *, named: bool = False):
    """Recursively order dict keys: preferred order first, the rest alphabetically.

    Entries of the named maps (``textures``, ``materials``) are sorted by name.
    """
    if isinstance(value, dict):
        if named:
            keys = sorted(value)
        else:
            keys = sorted(value, key=lambda k: (_KEY_RANK.get(k, len(_KEY_RANK)), k))
        return {k: _ordered(value[k], named=(not named and k in _NAMED_MAPS)) for k in keys}
    if isinstance(value, list):
        return [_ordered(v) for v in value]
    return value


def dump_scene_spec(spec: dict) -> str:
    """Deterministic YAML text of a spec (see :func:`write_scene_spec`)."""
    import yaml

    class _Dumper(yaml.SafeDumper):
        pass

    def _list(dumper, data):
        flow = all(not isinstance(x, (dict, list)) for x in data) or all(
            isinstance(x, list) and all(not isinstance(y, (dict, list)) for y in x) for x in data
        )
        return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)

    _Dumper.add_representer(list, _list)
    data = _ordered(plain(spec, ndigits=4, strict=True))
    return yaml.dump(
        data,
        Dumper=_Dumper,
        sort_keys=False,
        default_flow_style=False,
        allow_unicode=False,
        width=100,
        indent=2,
    )


def write_scene_spec(spec: dict, path) -> Path:
    """Write a spec as deterministic YAML, atomically.

    Parameters
    ----------
    spec : dict
        The spec to write (plain Python or numpy values).
    path : str or os.PathLike
        Destination; its directory is created if needed.

    Returns
    -------
    pathlib.Path
        The written path.

    Notes
    -----
    Keys follow a fixed order (``name``, ``description``, ``generator``, ``camera``,
    ``textures``, ``materials``, ``objects``, ``lights``; inside entries ``name``, ``shape``,
    ``type``, ... and ``translate``, ``rotate``, ``scale``; named maps alphabetically), floats
    are rounded to 4 decimals (``-0.0`` becomes ``0.0``) and lists of numbers are written in
    flow style, so the same spec always gives the same bytes. The text goes to a temporary
    file in the destination directory, which then replaces the destination with
    :func:`os.replace`.
    """
    path = Path(path)
    text = dump_scene_spec(spec)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path
