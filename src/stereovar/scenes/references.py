"""The files a Mitsuba XML scene reads: meshes, textures, spectra and included XML files.

A scene spec with ``mitsuba_xml`` renders whatever that file and the files it names contain,
so all of them determine the pixels: the workflow tracks them as inputs of the jobs that
load the scene, and :func:`stereovar.scenes.spec.scene_digest` hashes their bytes.

Mitsuba 3 names a file in two ways: a ``filename`` attribute (``<include filename=...>``,
``<spectrum filename=...>``) and a ``<string name="filename" value=...>`` parameter of a
plugin (``obj``, ``ply`` and ``serialized`` shapes, ``bitmap`` textures, ``envmap``
emitters). ``$name`` references are expanded with the ``<default>`` values of the files read
so far. A relative path is found next to the file that names it, else next to the top-level
scene file (the directory Mitsuba's file resolver adds).
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

from ..errors import SceneError

_VARIABLE = re.compile(r"\$(\w+)|\$\{(\w+)\}")


def _expand(value: str, defaults: dict, source: Path) -> str:
    def sub(match):
        name = match.group(1) or match.group(2)
        if name not in defaults:
            raise SceneError(
                f"{source}: ${name} is used in a file name but has no <default name={name!r} "
                "value=...>; add the default or write the path out"
            )
        return defaults[name]

    return _VARIABLE.sub(sub, value)


def _parse(path: Path) -> ET.Element:
    try:
        return ET.parse(path).getroot()
    except ET.ParseError as err:
        line, column = err.position
        reason = str(err).split(":")[0]
        raise SceneError(
            f"{path}: malformed XML at line {line}, column {column + 1} ({reason}); fix the file"
        ) from None
    except OSError as err:
        raise SceneError(f"cannot read Mitsuba scene file {path}: {err.strerror}") from None


def _resolve(name: str, here: Path, top: Path, source: Path) -> Path:
    candidate = Path(name).expanduser()
    if candidate.is_absolute():
        found = [candidate]
    else:
        found = [here / candidate, top / candidate]
    for path in found:
        if path.is_file():
            return path.resolve()
    raise SceneError(
        f"{source}: referenced file {name!r} not found (looked in {here}"
        + (f" and {top}" if top != here else "")
        + "); fix the path or add the file"
    )


def xml_references(path) -> list[Path]:
    """Every file a Mitsuba XML scene reads, includes followed recursively.

    Parameters
    ----------
    path : path-like
        The top-level scene file.

    Returns
    -------
    list of pathlib.Path
        Absolute paths without duplicates, in the order first named; the scene file itself is
        not listed.

    Raises
    ------
    SceneError
        One line: the file, or a file it includes, is not well-formed XML (with the line and
        column), a referenced file does not exist, a ``$name`` has no default, or the
        includes form a cycle.
    """
    top = Path(path).expanduser().resolve()
    found: list[Path] = []
    defaults: dict[str, str] = {}

    def visit(source: Path, chain: tuple[Path, ...]) -> None:
        root = _parse(source)
        here = source.parent
        for element in root.iter():
            if element.tag == "default" and "name" in element.attrib:
                defaults.setdefault(element.attrib["name"], element.attrib.get("value", ""))
        for element in root.iter():
            names = []
            if "filename" in element.attrib:
                names.append(element.attrib["filename"])
            if element.tag == "string" and element.attrib.get("name") == "filename":
                names.append(element.attrib.get("value", ""))
            for raw in names:
                target = _resolve(_expand(raw, defaults, source), here, top.parent, source)
                if element.tag == "include":
                    if target in chain:
                        raise SceneError(
                            f"{source}: <include filename={raw!r}> includes itself "
                            "(directly or through other files); remove the cycle"
                        )
                    if target not in found:
                        found.append(target)
                    visit(target, (*chain, target))
                elif target not in found:
                    found.append(target)

    visit(top, (top,))
    return found
