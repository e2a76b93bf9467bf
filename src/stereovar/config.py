"""Validate the workflow config and report problems in one line.

The JSON Schema ``workflow/schemas/config.schema.yaml`` defines the keys, types and
defaults. :func:`validate_config` checks a config against it, adds the checks that span
several keys, and raises :class:`~stereovar.errors.ConfigError` whose message names the
full dotted key, the value given and what is allowed, e.g.::

    config key 'rig.convention': 'left' is not allowed; use one of: paper, conventional

In a Snakefile, :func:`validate_config_or_exit` prints that line and stops Snakemake
without a Python traceback.
"""

from __future__ import annotations

import os
from collections.abc import Mapping

import jsonschema

from .errors import ConfigError, exit_with_one_line
from .schema import MAX_YAML_VALUES, expanded_size, fill_defaults, load_yaml, plain

__all__ = [
    "check_config_files_or_exit",
    "load_config",
    "merge_configs",
    "validate_config",
    "validate_config_or_exit",
]

#: Keys a user may write under ``audit:`` to ask for one render per view, which the audit
#: refuses with its measured reasons (:func:`stereovar.estimators.single.refusal`), as it
#: does N = 1 renders.
ONE_RENDER_KEYS = frozenset(
    {"single_render", "one_render", "single_image", "one_render_per_view", "single_view_render"}
)

_TYPE_NAMES = {
    "integer": "an integer",
    "number": "a number",
    "string": "a string",
    "array": "a list",
    "object": "a mapping of keys to values",
    "boolean": "true or false",
    "null": "null",
}


def _load_schema(schema_path) -> dict:
    schema_path = os.fspath(schema_path)
    if schema_path.startswith("file://"):
        schema_path = schema_path[len("file://") :]
    schema = load_yaml(schema_path, "config schema")
    if not isinstance(schema, dict):
        raise ConfigError(f"config schema '{schema_path}' is not a mapping")
    return schema


def _coerced(value: str, subschema: Mapping):
    """``value`` as the scalar type ``subschema`` allows (unchanged when none fits)."""
    kinds = subschema.get("type", [])
    kinds = [kinds] if isinstance(kinds, str) else list(kinds)
    text = value.strip().lower()
    if "null" in kinds and text in ("null", "~"):
        return None
    if "string" in kinds:
        return value
    if "boolean" in kinds and text in ("true", "false"):
        return text == "true"
    for kind in ("integer", "number"):
        if kind in kinds:
            try:
                number = float(value)
            except ValueError:
                continue
            if kind == "integer" and number.is_integer():
                return int(number)
            if kind == "number":
                return number
    return value


def _coerce_strings(instance: dict, schema: Mapping, given: Mapping) -> None:
    """Turn the strings given on the command line into the numbers, booleans or nulls the
    schema asks for, in place.

    ``snakemake --config key={a: 1}`` (and a profile's ``config:``) passes nested values as
    strings ("1"), list items included (``render={spp: [4]}`` gives ``["4"]``); a string
    there that parses as an allowed scalar type becomes that scalar. Only keys present in
    ``given`` (the ``--config`` mapping) are touched: a quoted number in a YAML config file
    stays an error.
    """
    for key, subschema in schema.get("properties", {}).items():
        if key not in given:
            continue
        value = instance.get(key)
        if isinstance(value, dict) and "properties" in subschema:
            if isinstance(given[key], Mapping):
                _coerce_strings(value, subschema, given[key])
            continue
        if isinstance(value, list) and isinstance(given[key], list) and value == given[key]:
            items = subschema.get("items", {})
            instance[key] = [_coerced(v, items) if isinstance(v, str) else v for v in value]
            continue
        if isinstance(value, str) and given[key] == value:
            instance[key] = _coerced(value, subschema)


def _key(path) -> str:
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


def _show(value) -> str:
    if value is None:
        text = "null"
    elif isinstance(value, bool):
        text = "true" if value else "false"
    else:
        text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _type_name(value) -> str:
    for name, python_type in (
        ("a boolean", bool),
        ("an integer", int),
        ("a number", float),
        ("a string", str),
        ("a list", list),
        ("a mapping", dict),
    ):
        if isinstance(value, python_type):
            return name
    return "null" if value is None else type(value).__name__


def _message(error: jsonschema.ValidationError) -> str:
    """One line for one schema violation."""
    path = list(error.absolute_path)
    key = _key(path)
    schema = error.schema if isinstance(error.schema, dict) else {}
    value = error.instance
    hint = schema.get("description", "")
    validator = error.validator
    if validator == "additionalProperties":
        allowed = list(schema.get("properties", {}))
        unknown = sorted(k for k in value if k not in allowed)
        where = f"under '{key}'" if key else "at the top level"
        if key == "audit" and set(unknown) & ONE_RENDER_KEYS:
            from .estimators.single import refusal

            return f"config key 'audit.{min(set(unknown) & ONE_RENDER_KEYS)}': {refusal()}"
        return (
            f"config key '{_key([*path, unknown[0]])}' is not known; allowed keys {where}: "
            f"{', '.join(allowed)}"
        )
    prefix = f"config key '{key}'" if key else "config"
    if validator == "type":
        expected = error.validator_value
        expected = expected if isinstance(expected, list) else [expected]
        names = " or ".join(_TYPE_NAMES.get(t, t) for t in expected)
        return f"{prefix}: expected {names}, got {_show(value)} ({_type_name(value)})"
    if validator == "enum":
        allowed = ", ".join(str(v) for v in error.validator_value)
        return f"{prefix}: {_show(value)} is not allowed; use one of: {allowed}"
    if validator in ("minimum", "exclusiveMinimum"):
        relation = ">=" if validator == "minimum" else ">"
        detail = f" ({hint})" if hint else ""
        return f"{prefix}: {_show(value)} is too small; use a value {relation} " + (
            f"{error.validator_value}{detail}"
        )
    if validator == "minItems":
        count = error.validator_value
        return (
            f"{prefix}: give at least {count} item{'s' if count != 1 else ''}, got {_show(value)}"
        )
    if validator == "uniqueItems":
        seen, repeated = [], []
        for item in value:
            (repeated if item in seen and item not in repeated else seen).append(item)
        return f"{prefix}: {', '.join(map(_show, repeated))} listed more than once; list each once"
    if validator == "pattern":
        detail = hint or f"match the pattern {error.validator_value}"
        return f"{prefix}: {_show(value)} is not allowed; use {detail}"
    if hint:
        return f"{prefix}: {_show(value)} is not allowed; expected {hint}"
    return f"{prefix}: {error.message}"


def _check_schema(config: dict, schema: dict) -> None:
    base = jsonschema.validators.validator_for(schema)
    # JSON Schema counts 64.0 as an integer; a sample count or a size must be a true integer.
    strict_int = base.TYPE_CHECKER.redefine(
        "integer", lambda _checker, v: isinstance(v, int) and not isinstance(v, bool)
    )
    validator_class = jsonschema.validators.extend(base, type_checker=strict_int)
    errors = list(validator_class(schema).iter_errors(config))
    if not errors:
        return
    errors.sort(key=lambda e: (len(e.absolute_path), [str(p) for p in e.absolute_path]))
    extra = len(errors) - 1
    more = f" (and {extra} more problem{'s' if extra > 1 else ''})" if extra else ""
    raise ConfigError(_message(errors[0]) + more)


def _check_cross_fields(config: dict) -> None:
    render = config.get("render", {})
    sweep = render.get("spp_sweep", {})
    spp, sweep_spp = render.get("spp"), sweep.get("spp")
    if spp is not None and sweep_spp is not None and spp not in sweep_spp:
        listed = ", ".join(str(s) for s in sweep_spp)
        raise ConfigError(
            f"config key 'render.spp_sweep.spp': [{listed}] does not include render.spp = "
            f"{spp}; add {spp} to render.spp_sweep.spp or set render.spp to one of: {listed}"
        )
    scenes, scene = config.get("scenes"), sweep.get("scene")
    if scenes is not None and scene is not None and scene not in scenes:
        raise ConfigError(
            f"config key 'render.spp_sweep.scene': {scene!r} is not in scenes; use one of: "
            f"{', '.join(scenes)} (or add it to scenes)"
        )
    _check_intervention(config)
    _check_bootstrap(config)
    _check_moments(config)
    _check_renderers(config)
    _check_cycles(config)


def _check_renderers(config: dict) -> None:
    """``renderers`` includes ``render.renderer``, the primary renderer."""
    runs = config.get("renderers")
    primary = config.get("render", {}).get("renderer", "mitsuba")
    if runs and primary not in runs:
        raise ConfigError(
            f"config key 'renderers': {runs} does not include render.renderer "
            f"{primary!r}, the primary renderer; add it or set render.renderer to one of: "
            f"{', '.join(runs)}"
        )


def _check_cycles(config: dict) -> None:
    """``render.renderer: cycles`` (or cycles in ``renderers``) refuses settings that would
    bias the measurement."""
    render = config.get("render", {})
    if "cycles" not in {render.get("renderer"), *(config.get("renderers") or [])}:
        return
    from .estimators import reads_moments

    if reads_moments(render.get("estimator")):
        raise ConfigError(
            "config key 'render.estimator': moments with the Cycles renderer; Cycles samples "
            "with scrambled quasi-Monte Carlo patterns, not the independent samples the "
            "moments estimator needs: set render.estimator: seeds"
        )
    from .renderers.cycles.settings import bounces, cycles_options_error

    error = cycles_options_error(render.get("cycles"), rfilter=render.get("rfilter", "box"))
    if error:
        raise ConfigError(error)
    try:
        bounces(render.get("max_depth", 8))
    except ValueError as err:
        raise ConfigError(f"config key 'render.max_depth': {err}") from None


MOMENTS_SAMPLER = "independent"
MOMENTS_FILTER = "box"


def moments_settings_error(sampler: str, rfilter: str) -> str | None:
    """Why ``render.estimator: moments`` cannot use ``sampler`` and ``rfilter`` (one line
    naming the key and the fix), or None when it can."""
    why = (
        "the moments estimator divides the per-sample variance by the SPP, which is the "
        "pixel variance only for independent samples that each land in their own pixel"
    )
    for key, value, needed in (
        ("sampler", sampler, MOMENTS_SAMPLER),
        ("rfilter", rfilter, MOMENTS_FILTER),
    ):
        if value != needed:
            return (
                f"config key 'render.{key}': {value!r} with render.estimator moments; {why}: "
                f"set render.{key}: {needed} or render.estimator: seeds"
            )
    return None


def _check_moments(config: dict) -> None:
    """``render.estimator: moments`` needs the independent sampler, the box filter and at
    least two samples per half render."""
    render = config.get("render", {})
    from .estimators import reads_moments

    if not reads_moments(render.get("estimator")):
        return
    error = moments_settings_error(
        render.get("sampler", MOMENTS_SAMPLER), render.get("rfilter", MOMENTS_FILTER)
    )
    if error:
        raise ConfigError(error)
    sweep = render.get("spp_sweep", {}).get("spp") or []
    low = sorted({s for s in [render.get("spp"), *sweep] if s is not None and s < 4})
    if low:
        key = "render.spp" if render.get("spp", 4) < 4 else "render.spp_sweep.spp"
        raise ConfigError(
            f"config key '{key}': SPP {', '.join(map(str, low))} with render.estimator "
            "moments; it renders each SPP as two half renders of at least 2 samples each: "
            "use an SPP of 4 or more"
        )


def _check_bootstrap(config: dict) -> None:
    tile = config.get("analysis", {}).get("bootstrap", {}).get("tile")
    res = config.get("resolution", {})
    width, height = res.get("width"), res.get("height")
    if tile is not None and width is not None and height is not None:
        if tile > min(width, height):
            raise ConfigError(
                f"config key 'analysis.bootstrap.tile': {tile} is larger than the "
                f"{width}x{height} image; use at most {min(width, height)} (16 is typical)"
            )


def _check_intervention(config: dict) -> None:
    intervention = config.get("intervention", {})
    window = intervention.get("window")
    if window is not None and window % 2 == 0:
        raise ConfigError(
            f"config key 'intervention.window': {window} is even; use an odd window "
            f"(e.g. {window + 1}) so it is centred on the pixel"
        )
    size = config.get("resolution", {})
    width, height = size.get("width"), size.get("height")
    if width is None or height is None:
        return
    smallest = min(width, height)
    # A window or block larger than the image leaves no pixel to score: every Table 3 row
    # would be NaN. The window is odd, so its bound is the largest odd side that fits.
    for key, largest in (("window", smallest - (smallest + 1) % 2), ("block", smallest)):
        value = intervention.get(key)
        if value is not None and value > smallest:
            raise ConfigError(
                f"config key 'intervention.{key}': {value} is larger than the image "
                f"({width}x{height}); use at most {largest}"
            )


def _check_size(config: Mapping, what: str) -> None:
    """Refuse a config that holds more than :data:`~stereovar.schema.MAX_YAML_VALUES` values
    once its shared references (YAML aliases) are expanded, or contains itself, before
    anything copies it; the message names the key that holds them."""

    def size(value) -> float:
        try:
            return expanded_size(value)
        except ValueError:
            return float("inf")

    total = size(config)
    if total <= MAX_YAML_VALUES:
        return
    # name the deepest mapping key that alone holds too many
    path, node, held = [], config, total
    while isinstance(node, Mapping) and node:
        key, largest = max(((k, size(v)) for k, v in node.items()), key=lambda kv: kv[1])
        if largest <= MAX_YAML_VALUES:
            break
        path.append(key)
        node, held = node[key], largest
        if held == float("inf"):
            break
    where = f"{what} key '{_key(path)}'" if path else what
    if held == float("inf"):
        raise ConfigError(
            f"{where}: contains itself (a recursive YAML alias); give the values in full"
        )
    raise ConfigError(
        f"{where}: holds {held:,} values once its YAML aliases are expanded, more than the "
        f"{MAX_YAML_VALUES:,} a config may hold; write the values out or repeat fewer aliases"
    )


def validate_config(config: Mapping, schema_path, *, command_line: Mapping | None = None) -> dict:
    """Check a workflow config and return it with every default filled in.

    Parameters
    ----------
    config : Mapping
        The config as loaded from YAML (Snakemake's ``config``); it is not modified.
    schema_path : str or os.PathLike
        The JSON Schema (YAML), ``workflow/schemas/config.schema.yaml``.
    command_line : Mapping, optional
        The ``--config`` entries; their string values are read as the schema's scalar type.

    Returns
    -------
    dict
        A deep copy of ``config`` with the schema's defaults inserted for missing keys.

    Raises
    ------
    ConfigError
        With a one-line message naming the dotted key and what is allowed, when a key is
        unknown, a value has the wrong type or is out of range, ``render.spp_sweep.spp``
        lacks ``render.spp``, ``render.spp_sweep.scene`` is not in ``scenes``, an
        intervention window or block is larger than the image, or the config holds more
        than :data:`~stereovar.schema.MAX_YAML_VALUES` values with its YAML aliases
        expanded (checked before anything is copied).
    """
    schema = _load_schema(schema_path)
    if config is None:
        config = {}
    if not isinstance(config, Mapping):
        raise ConfigError(
            f"config: expected a mapping of keys to values, got {_show(config)} "
            f"({_type_name(config)})"
        )
    _check_size(config, "config")
    _check_size(command_line or {}, "--config")
    filled = plain(config)
    _coerce_strings(filled, schema, plain(command_line or {}))
    fill_defaults(filled, schema)
    _check_schema(filled, schema)
    _check_cross_fields(filled)
    _check_registered(filled)
    return filled


def _check_registered(config: dict) -> None:
    """The renderer, estimator and seed policy the config names are implemented."""
    from .estimators import ESTIMATORS
    from .renderers import RENDERERS
    from .seeding import SEED_POLICIES

    render = config.get("render", {})
    for key, registry in (
        ("renderer", RENDERERS),
        ("estimator", ESTIMATORS),
        ("seed_policy", SEED_POLICIES),
    ):
        if key in render and render[key] not in registry:
            registry.get(render[key])  # raises the one-line error listing what exists
    _check_mitigations(config)


def _check_mitigations(config: dict) -> None:
    """Every ``mitigations.names`` entry is a mitigation (:mod:`stereovar.mitigations`)."""
    from .mitigations import resolve_mitigation

    for name in config.get("mitigations", {}).get("names", []):
        resolve_mitigation(name)  # raises the one-line error listing what exists


def validate_config_or_exit(
    config: Mapping, schema_path, *, command_line: Mapping | None = None
) -> dict:
    """:func:`validate_config` for Snakefiles: on error print one line and exit.

    Raising :class:`ConfigError` inside a Snakefile makes Snakemake print the error type,
    the file and line and a traceback of workflow frames. ``SystemExit`` with a message
    makes it print only the message (to stderr) and exit with status 1.

    Parameters
    ----------
    config : Mapping
        Snakemake's ``config``.
    schema_path : str or os.PathLike
        The JSON Schema (YAML), e.g. ``workflow.source_path("../schemas/config.schema.yaml")``.
    command_line : Mapping, optional
        The ``--config`` entries (``workflow.config_settings.config``).

    Returns
    -------
    dict
        See :func:`validate_config`.

    Raises
    ------
    SystemExit
        With the message ``stereovar: <one-line ConfigError message>``.
    """
    with exit_with_one_line():
        return validate_config(config, schema_path, command_line=command_line)


def merge_configs(base: Mapping, override: Mapping) -> dict:
    """Merge two configs the way Snakemake merges ``--configfile`` files.

    Parameters
    ----------
    base, override : Mapping
        ``override`` wins; nested mappings are merged key by key, everything else
        (lists included) is replaced.

    Returns
    -------
    dict
        A new config; the inputs are not modified.
    """
    merged = plain(base)
    for key, value in override.items():
        if isinstance(value, Mapping) and isinstance(merged.get(key), dict):
            merged[key] = merge_configs(merged[key], value)
        else:
            merged[key] = plain(value)
    return merged


def load_config(path, schema_path) -> dict:
    """Load, merge and validate config files, for notebooks and tests.

    Parameters
    ----------
    path : str, os.PathLike or sequence of them
        A YAML config file, or several merged in order (later files win, as with
        ``snakemake --configfile``), e.g. ``["config.yaml", "workflow/presets/paper.yaml"]``.
    schema_path : str or os.PathLike
        The JSON Schema (YAML).

    Returns
    -------
    dict
        The validated config with defaults filled in.

    Raises
    ------
    ConfigError
        If a file is missing, is not valid YAML, is not a mapping, or the merged config is
        invalid (see :func:`validate_config`).
    """
    paths = [path] if isinstance(path, str | os.PathLike) else list(path)
    if not paths:
        raise ConfigError("load_config: give at least one config file")
    merged: dict = {}
    for one in paths:
        loaded = load_yaml(one, "config file")
        if loaded is None:
            loaded = {}
        if not isinstance(loaded, Mapping):
            raise ConfigError(
                f"config file '{one}' must hold a mapping of keys to values, "
                f"got {_type_name(loaded)}"
            )
        merged = merge_configs(merged, loaded)
    return validate_config(merged, schema_path)


def check_config_files_or_exit(paths) -> None:
    """Read each workflow config file as stereovar reads YAML (:func:`~stereovar.schema.load_yaml`),
    and stop with one line naming the file, the line and the problem.

    Snakemake reads config files with a loader that builds the Python objects some tags
    name (``!!python/name:...``) and reports a tag it refuses as "Config file is not valid
    JSON or YAML", without the file or the tag; and it loads aliases that expand past what
    a config may hold. Run before the ``configfile:`` directive, this names both. A file
    that is valid JSON is left to Snakemake (JSON has neither tags nor aliases); a file
    that does not exist is left to Snakemake's own message.

    Parameters
    ----------
    paths : iterable of str or os.PathLike
        The workflow's config files (``config.yaml`` and ``--configfile`` files).

    Raises
    ------
    SystemExit
        With the message ``stereovar: <one-line ConfigError message>``.
    """
    import json
    from pathlib import Path

    cwd = Path.cwd()
    for path in paths:
        path = Path(path)
        if path.is_absolute() and path.is_relative_to(cwd):
            path = path.relative_to(cwd)  # as given on the command line
        try:
            json.loads(path.read_text(encoding="utf-8"))
            continue
        except (OSError, UnicodeDecodeError):
            continue
        except ValueError:
            pass
        with exit_with_one_line():
            load_yaml(path, "config file")
