"""Pages of the stereovar documentation that are generated from the code at build time.

Sections that would go stale if written by hand are written here, before Sphinx reads the
sources, into ``docs/_generated/`` (included by the hand-written pages, never read on their
own):

``config_keys.rst``
    every key of the workflow's JSON Schema (``workflow/schemas/config.schema.yaml``): its
    type, default, the values allowed and the schema's description, with the value
    ``config.yaml`` sets where it differs from the schema's default;
``source_tree.rst``
    every package and module under ``src/stereovar`` with the first sentence of its
    docstring, and the data files shipped with them;
``workflow_map.rst``
    each rule file of ``workflow/rules`` with its rules and the input functions it calls
    (``workflow/rules/inputs/``), and the library modules those ask;
``result_paths.rst``, ``layout_doc.rst``
    every path of :mod:`stereovar.layout`, obtained by calling its functions with the
    wildcards as arguments, and the module's own description;
``top_level_names.rst``
    the names ``import stereovar`` exposes and the object each one is;
``cli.rst``
    the ``--help`` of the ``stereovar`` command and of each of its commands.

A file is rewritten only when its content changes, so an unchanged build stays incremental.
Before autosummary writes the API pages (``docs/api/``), the pages of modules that no longer
exist are removed, so a renamed module cannot leave a page behind that fails to import.
"""

from __future__ import annotations

import ast
import importlib
import inspect
import re
import warnings
from pathlib import Path

import yaml

GENERATED = "_generated"


# --- helpers -----------------------------------------------------------------------------


def write_if_changed(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` unless it already holds exactly that."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.is_file() and path.read_text(encoding="utf-8") == text:
        return
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(path)


def literal(value) -> str:
    """``value`` as an inline reStructuredText literal (YAML flow style for data)."""
    if isinstance(value, str):
        text = value
    else:
        text = yaml.safe_dump(value, default_flow_style=True, width=10_000).strip()
        if text.endswith("\n...") or text.endswith(" ..."):
            text = text[: -len("...")].rstrip()
    text = " ".join(text.split())
    return f"``{text}``" if text else "``''``"


_INLINE_SPECIAL = re.compile(r"([\\*_|<>\[\]])")


def rst_text(text: str) -> str:
    """Plain text (the schema's descriptions) as reStructuredText: Markdown-style
    ```code``` spans become literals, everything else is escaped."""
    out = []
    for i, part in enumerate(re.split(r"`([^`]+)`", " ".join(str(text).split()))):
        if i % 2:
            out.append(f"``{part}``")
        else:
            out.append(_INLINE_SPECIAL.sub(r"\\\1", part))
    return "".join(out)


def list_table(header: list[str], rows: list[list[str]], widths: list[int]) -> list[str]:
    lines = [
        ".. list-table::",
        "   :header-rows: 1",
        f"   :widths: {' '.join(str(w) for w in widths)}",
        "   :class: config-table",
        "",
    ]
    for row in [header, *rows]:
        for j, cell in enumerate(row):
            bullet = f"   {'*' if j == 0 else ' '} -"
            cell_lines = str(cell).split("\n")
            lines.append(f"{bullet} {cell_lines[0]}".rstrip())
            lines.extend(f"       {line}".rstrip() for line in cell_lines[1:])
    lines.append("")
    return lines


# --- the configuration reference ------------------------------------------------------------


def schema_path(repo: Path) -> Path:
    """The workflow's config schema: the checkout's, else the packaged workflow's."""
    for candidate in (
        repo / "workflow" / "schemas" / "config.schema.yaml",
        repo / "src" / "stereovar" / "_workflow" / "workflow" / "schemas" / "config.schema.yaml",
    ):
        if candidate.is_file():
            return candidate
    raise FileNotFoundError(f"no workflow/schemas/config.schema.yaml under {repo}")


def schema_keys(schema: dict, prefix: str = ""):
    """``(dotted key, subschema, required)`` of every property, depth first in schema order."""
    required = set(schema.get("required", ()))
    for name, sub in (schema.get("properties") or {}).items():
        key = f"{prefix}{name}"
        yield key, sub, name in required
        if sub.get("type") == "object" or "properties" in sub:
            yield from schema_keys(sub, f"{key}.")


def type_text(sub: dict) -> str:
    kinds = sub.get("type")
    if kinds is None:
        if "enum" in sub:
            kinds = sorted({type(v).__name__ for v in sub["enum"]} - {"NoneType"})
            kinds = [{"str": "string", "int": "integer", "float": "number"}.get(k, k)
                     for k in kinds]
            if None in sub["enum"]:
                kinds.append("null")
        elif "const" in sub:
            kinds = [type(sub["const"]).__name__]
        else:
            return "any"
    if isinstance(kinds, str):
        kinds = [kinds]
    text = " or ".join(kinds)
    items = sub.get("items")
    if "array" in kinds and isinstance(items, dict) and items.get("type"):
        item_type = items["type"]
        item_type = " or ".join(item_type) if isinstance(item_type, list) else item_type
        text = text.replace("array", f"array of {item_type}")
    return text


def bounds(sub: dict) -> list[str]:
    parts = []
    for key, sign in (("minimum", ">="), ("exclusiveMinimum", ">"), ("maximum", "<="),
                      ("exclusiveMaximum", "<")):
        if key in sub:
            parts.append(f"{sign} {sub[key]}")
    return parts


def allowed_text(sub: dict, required: bool) -> str:
    """The values a key allows, in words."""
    parts = []
    if required:
        parts.append("required")
    if "enum" in sub:
        parts.append("one of " + ", ".join(literal(v) for v in sub["enum"]))
    if "const" in sub:
        parts.append(literal(sub["const"]))
    parts.extend(bounds(sub))
    if "anyOf" in sub:
        options = []
        for option in sub["anyOf"]:
            if "const" in option:
                options.append(literal(option["const"]))
            else:
                options.extend(bounds(option))
        parts.append(", or ".join(options))
    if "pattern" in sub:
        parts.append(f"matches {literal(sub['pattern'])}")
    if "minLength" in sub:
        parts.append(f"at least {sub['minLength']} characters")
    if "minItems" in sub:
        parts.append(f"at least {sub['minItems']} item{'s' if sub['minItems'] > 1 else ''}")
    if sub.get("uniqueItems"):
        parts.append("no repeats")
    items = sub.get("items")
    if isinstance(items, dict):
        inner = allowed_text(items, False)
        if inner:
            parts.append(f"each item {inner}")
    if sub.get("required"):
        parts.append("needs " + ", ".join(literal(k) for k in sub["required"]))
    return "; ".join(p for p in parts if p)


def lookup(config: dict, key: str):
    node = config
    for part in key.split("."):
        if not isinstance(node, dict) or part not in node:
            raise KeyError(key)
        node = node[part]
    return node


def config_reference(schema: dict, config: dict) -> str:
    """The configuration reference: one section per top-level key, one row per key."""
    lines = [
        ".. This file is generated from the workflow's config schema by",
        "   docs/_ext/stereovar_docs.py; edit the schema, not this file.",
        "",
    ]
    keys = list(schema_keys(schema))
    sections = [k for k, _, _ in keys if "." not in k]
    for top in sections:
        sub = schema["properties"][top]
        lines += [f".. _config-{top}:", "", f"``{top}``", "~" * (len(top) + 4), ""]
        if sub.get("description"):
            lines += [rst_text(sub["description"]), ""]
        rows = []
        for key, ksub, required in keys:
            if key != top and not key.startswith(f"{top}."):
                continue
            if "default" in ksub:
                default = literal(ksub["default"])
            else:
                default = "no default" if required else "not set"
            try:
                set_here = lookup(config, key)
            except KeyError:
                pass
            else:
                if "default" not in ksub or set_here != ksub["default"]:
                    if not isinstance(set_here, dict):
                        default += f"; ``config.yaml``: {literal(set_here)}"
            rows.append([
                f"``{key}``",
                rst_text(type_text(ksub)),
                default,
                allowed_text(ksub, required),
                rst_text(ksub.get("description", "")),
            ])
        lines += list_table(["key", "type", "default", "allowed", "meaning"], rows,
                            [18, 10, 16, 16, 40])
    return "\n".join(lines) + "\n"


# --- the source tree ----------------------------------------------------------------------------


def first_sentence(doc: str | None) -> str:
    """The first sentence of a docstring's first paragraph."""
    if not doc:
        return ""
    paragraph = " ".join(inspect.cleandoc(doc).split("\n\n")[0].split())
    return re.split(r"(?<=[.!?])\s+(?=[A-Z])", paragraph)[0]


def module_doc(path: Path) -> str | None:
    return ast.get_docstring(ast.parse(path.read_text(encoding="utf-8")))


def data_file_doc(path: Path) -> str:
    """What a data file shipped with the package is: a YAML file's ``title`` or
    ``description``, or its first comment line."""
    text = path.read_text(encoding="utf-8", errors="replace")
    if path.suffix in (".yaml", ".yml"):
        try:
            data = yaml.safe_load(text)
        except yaml.YAMLError:
            data = None
        if isinstance(data, dict):
            for key in ("title", "description"):
                if isinstance(data.get(key), str):
                    return data[key]
    for line in text.splitlines():
        if line.startswith("#"):
            return line.lstrip("#").strip()
    return ""


def package_tree(root: Path, package: str, depth: int = 0) -> list[str]:
    """Bullet lines of one package: its modules, data files and subpackages."""
    indent = "  " * depth
    lines = []
    init = root / "__init__.py"
    doc = first_sentence(module_doc(init)) if init.is_file() else ""
    head = f"{indent}- :mod:`{package}`"
    lines.append(f"{head} -- {doc}" if doc else head)
    lines.append("")
    inner = "  " * (depth + 1)
    for path in sorted(root.iterdir()):
        if path.name.startswith(("_", ".")) or path.name == "__pycache__":
            continue
        if path.is_dir():
            if any(path.glob("*.py")):
                lines += package_tree(path, f"{package}.{path.name}", depth + 1)
            continue
        if path.suffix == ".py":
            name = f"{package}.{path.stem}"
            doc = first_sentence(module_doc(path))
            lines.append(f"{inner}- :mod:`{name}`" + (f" -- {doc}" if doc else ""))
        elif path.suffix in (".yaml", ".yml", ".json"):
            doc = data_file_doc(path)
            rel = path.relative_to(root.parents[depth]) if depth else path.name
            lines.append(f"{inner}- ``{rel}``" + (f" -- {rst_text(doc)}" if doc else ""))
        else:
            continue
        lines.append("")
    return lines


def source_tree(src: Path) -> str:
    lines = [
        ".. This file is generated from the modules' docstrings by",
        "   docs/_ext/stereovar_docs.py.",
        "",
    ]
    lines += package_tree(src / "stereovar", "stereovar")
    return "\n".join(lines) + "\n"


# --- the workflow's rule files and their input functions ------------------------------------

_RULE = re.compile(r"^(?:rule|checkpoint) (\w+):", re.M)
_FUNCTION = re.compile(r"^def (\w+)\(", re.M)
_LIBRARY = re.compile(r"^from stereovar\.workflow_inputs import (\w+) as (\w+)", re.M)


def workflow_map(rules: Path) -> str:
    """Two tables from ``workflow/rules``: each rule file with its rules and the files whose
    functions it calls (``common.smk``, shared, and ``inputs/<feature>.smk``), then each
    input file with its functions and the :mod:`stereovar.workflow_inputs` modules it asks."""
    sources = {"common.smk": (rules / "common.smk").read_text(encoding="utf-8")}
    for path in sorted(rules.glob("inputs/*.smk")):
        sources[f"inputs/{path.name}"] = path.read_text(encoding="utf-8")
    defined = {name: set(_FUNCTION.findall(text)) for name, text in sources.items()}
    aliases = {a: m for text in sources.values() for m, a in _LIBRARY.findall(text)}
    rows = []
    for path in sorted(rules.glob("*.smk")):
        text = path.read_text(encoding="utf-8")
        names = _RULE.findall(text)
        if not names:
            continue
        words = set(re.findall(r"\b(\w+)\b", text))
        used = [f"``{n}``" for n, funcs in defined.items() if funcs & words]
        rows.append([
            f"``{path.name}``",
            ", ".join(f"``{r}``" for r in names),
            ", ".join(used) or "--",
        ])
    lines = [
        ".. This file is generated from workflow/rules by docs/_ext/stereovar_docs.py.",
        "",
    ]
    lines += list_table(["rule file", "rules", "functions from"], rows, [18, 52, 30])
    rows = []
    for name, text in sources.items():
        library = [
            f":mod:`stereovar.workflow_inputs.{m}`"
            for a, m in sorted(aliases.items(), key=lambda am: am[1])
            if re.search(rf"\b{a}\.", text)
        ]
        rows.append([
            f"``{name}``",
            ", ".join(f"``{f}``" for f in sorted(defined[name])) or "--",
            ", ".join(library) or "--",
        ])
    lines += list_table(["file", "functions", "library"], rows, [22, 50, 28])
    return "\n".join(lines) + "\n"


# --- the result paths -----------------------------------------------------------------------


def _placeholder(name: str) -> str:
    return "{format}" if name == "fmt" else "{" + name + "}"


def path_patterns(func) -> list[str]:
    """The path patterns a :mod:`stereovar.layout` function returns, wildcards in braces:
    one call with every argument a wildcard (transform left out), one with the transform
    given, and, for a function whose ``source`` may be None, one for the run and one for an
    audit. Lists of table paths are folded into ``{csv,md,...}``."""
    sig = inspect.signature(func)
    required = {}
    optional = {}
    for name, param in sig.parameters.items():
        if param.kind not in (param.POSITIONAL_OR_KEYWORD, param.KEYWORD_ONLY):
            return []
        if param.default is param.empty:
            required[name] = _placeholder(name)
        else:
            optional[name] = param.default
    calls = [dict(required)]
    if "transform" in optional:
        calls.append({**required, "transform": "{transform}"})
    if "source" in optional:
        calls = [dict(required), {**required, "source": "audit/{name}"}]
    elif "source" in required and "transform" not in optional:
        calls.append({**required, "source": "audit/{name}"})
    if set(optional) - {"transform", "source"}:
        return []
    out = []
    for kwargs in calls:
        value = func(**kwargs)
        values = value if isinstance(value, list) else [value]
        if not values or not all(isinstance(v, str) for v in values):
            return []
        if len(values) > 1:
            stems = {v.rsplit(".", 1)[0] for v in values}
            if len(stems) == 1:
                exts = ",".join(v.rsplit(".", 1)[1] for v in values)
                values = [f"{stems.pop()}.{{{exts}}}"]
        if kwargs.get("source") == "audit/{name}" and "source" in required:
            # an audit's path that is the run's with the source filled in adds nothing
            plain = out[0].replace("{source}", "audit/{name}")
            values = [v for v in values if v != plain]
        out.extend(v for v in values if v not in out)
    if len(out) == 2 and "transform" in optional:
        plain, with_transform = out
        if with_transform == plain.replace("{source}", "{source}/{transform}", 1):
            out = [plain.replace("{source}", "{source}[/{transform}]", 1)]
    return out


def result_paths(layout) -> str:
    lines = [
        ".. This file is generated from stereovar.layout by docs/_ext/stereovar_docs.py.",
        "",
    ]
    rows = []
    for name, func in inspect.getmembers(layout, inspect.isfunction):
        if name.startswith("_") or func.__module__ != layout.__name__:
            continue
        try:
            patterns = path_patterns(func)
        except (TypeError, ValueError):
            continue
        patterns = [p for p in patterns if p.startswith(layout.RESULTS + "/")]
        if not patterns:
            continue
        doc = first_sentence(inspect.getdoc(func))
        what = rst_text_keep_roles(re.split(r":\s*``|:$", doc)[0].rstrip(" :,"))
        rows.append((patterns, what, name))
    rows.sort()
    # a definition list: long paths do not fit a table column
    for patterns, what, name in rows:
        lines.append(", ".join(f"``{p}``" for p in patterns))
        lines.append(f"   {what} (:func:`~stereovar.layout.{name}`).")
        lines.append("")
    return "\n".join(lines) + "\n"


def layout_doc(layout) -> str:
    """The docstring of :mod:`stereovar.layout`, its cross-references made absolute."""
    doc = inspect.getdoc(layout) or ""
    doc = re.sub(r":(data|func):`(?![~.]|stereovar)([^`]+)`", r":\1:`~stereovar.layout.\2`", doc)
    return ".. Generated from the docstring of stereovar.layout.\n\n" + doc + "\n"


def rst_text_keep_roles(text: str) -> str:
    """A docstring fragment is reStructuredText already; only a dangling literal is closed."""
    if text.count("``") % 2:
        text += "``"
    return text


# --- the names of ``import stereovar`` ------------------------------------------------------------


def top_level_names() -> str:
    """A table of ``stereovar.__all__``: each name with the object it is and where it is
    documented."""
    import stereovar

    lines = [
        ".. This file is generated from stereovar.__all__ by docs/_ext/stereovar_docs.py.",
        "",
    ]
    rows = []
    for name in stereovar.__all__:
        if name.startswith("__"):
            continue
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            obj = getattr(stereovar, name)
        deprecated = any(issubclass(w.category, DeprecationWarning) for w in caught)
        owner = None
        if inspect.isclass(obj) or inspect.isfunction(obj):
            module = obj.__module__
            kind = "class" if inspect.isclass(obj) else "func"
            ref = f":{kind}:`{name} <{module}.{obj.__qualname__}>`"
        else:
            owner = module = _defining_module(stereovar, name)
            ref = f":data:`{name} <{owner}.{name}>`" if owner else f"``{name}``"
        if callable(obj):
            summary = first_sentence(inspect.getdoc(obj))
        else:
            summary = first_sentence(_attribute_doc(owner, name)) if owner else ""
        where = [f":mod:`{module}`"] if module else []
        if deprecated:
            where.append("deprecated alias")
        summary = rst_text_keep_roles(summary)
        if where:
            summary = f"{summary} ({'; '.join(where)})" if summary else "; ".join(where)
        rows.append([ref, summary])
    lines += list_table(["name", "what it is"], rows, [30, 70])
    return "\n".join(lines) + "\n"


def _attribute_doc(module: str, name: str) -> str:
    """The docstring written under a module-level assignment (as autodoc reads it)."""
    from sphinx.pycode import ModuleAnalyzer

    try:
        docs = ModuleAnalyzer.for_module(module).find_attr_docs()
    except Exception:  # a module without readable source documents nothing here
        return ""
    return "\n".join(docs.get(("", name), []))


def _defining_module(package, name: str) -> str | None:
    """The module a non-callable public name (a registry, a table of constants) comes from,
    as the package's lazy-import table or its stub file says."""
    table = getattr(package, "_API", None)
    if isinstance(table, dict) and name in table:
        return f"{package.__name__}.{table[name]}"
    stub = Path(package.__file__).with_suffix(".pyi")
    if stub.is_file():
        for node in ast.walk(ast.parse(stub.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and any(
                (alias.asname or alias.name) == name for alias in node.names
            ):
                base = package.__name__.rsplit(".", node.level - 1)[0] if node.level else ""
                return f"{base}.{node.module}" if base else node.module
    return None


# --- the command line ---------------------------------------------------------------------


def cli_help() -> str:
    """``stereovar --help`` and each command's ``--help``, as the parser prints them."""
    import argparse
    import os

    from stereovar.cli import build_parser

    lines = [
        ".. This file is generated from stereovar.cli.build_parser by",
        "   docs/_ext/stereovar_docs.py.",
        "",
    ]
    saved = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "92"
    try:
        parser = build_parser()
        pages = [("stereovar", parser)]
        queue = [("stereovar", parser)]
        while queue:
            prefix, current = queue.pop(0)
            for action in current._actions:
                if isinstance(action, argparse._SubParsersAction):
                    for name, sub in action.choices.items():
                        pages.append((f"{prefix} {name}", sub))
                        queue.append((f"{prefix} {name}", sub))
        for title, sub in pages:
            lines += [f"``{title} --help``", "", "::", ""]
            lines += [f"   {line}".rstrip() for line in sub.format_help().splitlines()]
            lines.append("")
    finally:
        if saved is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = saved
    return "\n".join(lines) + "\n"


# --- Sphinx -------------------------------------------------------------------------------


def generate(app) -> None:
    docs = Path(app.confdir)
    repo = docs.parent
    out = docs / GENERATED
    schema = yaml.safe_load(schema_path(repo).read_text(encoding="utf-8"))
    config_file = repo / "config.yaml"
    config = {}
    if config_file.is_file():
        config = yaml.safe_load(config_file.read_text(encoding="utf-8")) or {}
    write_if_changed(out / "config_keys.rst", config_reference(schema, config))
    write_if_changed(out / "source_tree.rst", source_tree(repo / "src"))
    write_if_changed(out / "workflow_map.rst", workflow_map(repo / "workflow" / "rules"))
    layout = importlib.import_module("stereovar.layout")
    write_if_changed(out / "result_paths.rst", result_paths(layout))
    write_if_changed(out / "layout_doc.rst", layout_doc(layout))
    write_if_changed(out / "top_level_names.rst", top_level_names())
    write_if_changed(out / "cli.rst", cli_help())


# The docstrings cite the paper as "Eq. 1", "Sec. 3.4", "Fig. 2": not the end of a sentence
# when autosummary picks a docstring's first sentence for its tables.
PAPER_ABBREVIATIONS = ("Eq.", "Eqs.", "Sec.", "Secs.", "Fig.", "Figs.", "cf.", "vs.")


def module_names(src: Path) -> set[str]:
    """Every module and package under ``src/stereovar`` by its dotted name."""
    names = set()
    for path in (src / "stereovar").rglob("*.py"):
        parts = path.relative_to(src).with_suffix("").parts
        names.add(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return names


def remove_stale_api_pages(app) -> None:
    """Remove the API pages of modules that no longer exist (autosummary writes pages but
    never removes one), before autosummary writes the current ones."""
    api = Path(app.confdir) / "api"
    if not api.is_dir():
        return
    current = module_names(Path(app.confdir).parent / "src")
    for stub in api.glob("stereovar*.rst"):
        if stub.stem not in current:
            stub.unlink()


def reuse_numpydoc_template() -> None:
    """Let numpydoc compile its docstring template once per build instead of once per
    docstring (numpydoc 1.8 builds a new Jinja environment for each of the ~2000 docstrings,
    a fifth of the time to read the API pages). Nothing changes when numpydoc's internals
    are not the ones this relies on."""
    from numpydoc import docscrape_sphinx, numpydoc

    original = getattr(docscrape_sphinx, "get_doc_object_orig", None)
    if original is None or not hasattr(numpydoc, "get_doc_object"):
        return
    from jinja2 import FileSystemLoader
    from jinja2.sandbox import SandboxedEnvironment
    from sphinx.jinja2glue import BuiltinTemplateLoader

    templates = {}

    def get_doc_object(obj, what=None, doc=None, config=None, builder=None):
        config = {} if config is None else config
        if builder not in templates:
            dirs = [str(Path(docscrape_sphinx.__file__).parent / "templates")]
            if builder is None:
                loader = FileSystemLoader(dirs)
            else:
                loader = BuiltinTemplateLoader()
                loader.init(builder, dirs=dirs)
            env = SandboxedEnvironment(loader=loader)
            templates[builder] = env.get_template("numpydoc_docstring.rst")
        config["template"] = templates[builder]
        return original(
            obj,
            what=what,
            doc=doc,
            config=config,
            class_doc=docscrape_sphinx.SphinxClassDoc,
            func_doc=docscrape_sphinx.SphinxFunctionDoc,
            obj_doc=docscrape_sphinx.SphinxObjDoc,
        )

    numpydoc.get_doc_object = get_doc_object


def visit_autosummary_table(self, node) -> None:
    """An API summary table's signatures may wrap before their arguments and between them,
    never inside a name: autosummary's own visitor joins them with no-break spaces, which
    pushed a summary table with long result paths past the article at 1280 px."""
    from docutils import nodes

    for row in node.findall(nodes.row):
        if not row.children or not row[0].children:
            continue
        par = row[0][0]
        if not isinstance(par, nodes.paragraph):
            continue
        for child in list(par.children):
            if isinstance(child, nodes.Text) and child.astext().startswith("("):
                par.insert(par.index(child), nodes.raw("", "<wbr>", format="html"))


def list_mock_decorated_functions() -> None:
    """List and summarise a function behind a decorator of a mocked module as a function.

    Where autodoc mocks PyTorch, ``@torch.no_grad()`` turns the function it decorates into a
    mock holding it. autodoc's own directives unwrap such a mock
    (:func:`sphinx.ext.autodoc.mock.undecorate`); autosummary's member lists and summary
    tables did not, so the function was left out of its module's page. Here both see the
    function itself (Sphinx is pinned in the docs extra, so these two names are known)."""
    from sphinx.ext import autosummary
    from sphinx.ext.autodoc.mock import undecorate
    from sphinx.ext.autosummary import generate

    if getattr(autosummary.get_documenter, "undecorates", False):
        return
    documenter, members = autosummary.get_documenter, generate._get_all_members

    def get_documenter(app, obj, parent):
        return documenter(app, undecorate(obj), parent)

    def get_all_members(doc, app, obj):
        return {name: undecorate(value) for name, value in members(doc, app, obj).items()}

    get_documenter.undecorates = True
    autosummary.get_documenter = generate.get_documenter = get_documenter
    generate._get_all_members = get_all_members


def setup(app):
    app.connect("builder-inited", remove_stale_api_pages, priority=100)
    reuse_numpydoc_template()
    from sphinx.ext import autosummary

    autosummary.WELL_KNOWN_ABBREVIATIONS = tuple(
        dict.fromkeys((*autosummary.WELL_KNOWN_ABBREVIATIONS, *PAPER_ABBREVIATIONS))
    )
    list_mock_decorated_functions()
    app.connect("builder-inited", generate)
    app.add_node(
        autosummary.autosummary_table,
        html=(visit_autosummary_table, autosummary.autosummary_noop),
        override=True,
    )
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
