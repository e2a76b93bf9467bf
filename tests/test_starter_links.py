"""The starter files that ``stereovar init`` writes (config.yaml and audit.yaml) point a user
at pages of the documentation site, never at paths of the source repository, which an
installed stereovar does not have."""

from __future__ import annotations

import contextlib
import io
import os
import re
from pathlib import Path
from urllib.parse import urlsplit

import pytest

from stereovar.links import DEFAULT_DOCS_URL

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"

#: Paths of the source repository that a comment must not send an installed user to.
REPOSITORY_PATHS = re.compile(r"\b(workflow|docs|profiles|schemas|presets|src)/|snakemake --report")
URL = re.compile(r"https?://[^\s)>\]'\"`]+")


def comments(text: str) -> str:
    """The comment part of every line of a YAML file."""
    return "\n".join(line.split("#", 1)[1] for line in text.splitlines() if "#" in line)


def docs_pages() -> set[str]:
    """The page names of the documentation site: the sources in docs/, without suffix."""
    return {p.stem for p in DOCS.iterdir() if p.suffix in (".md", ".rst")}


def page_of(url: str) -> str | None:
    """The page a docs address names (``""`` for the front page), or None when the address
    is not the documentation's.

    Examples
    --------
    >>> page_of("https://stereovar.readthedocs.io/en/latest/audit.html#verdict")
    'audit'
    >>> page_of("https://example.org/audit.html") is None
    True
    """
    if not url.startswith(DEFAULT_DOCS_URL):
        return None
    path = urlsplit(url[len(DEFAULT_DOCS_URL) :]).path
    return path.removesuffix(".html") if path.endswith(".html") or not path else None


@pytest.fixture(scope="module")
def starters(tmp_path_factory) -> dict[str, str]:
    """The files ``stereovar init`` writes in an empty directory, by name."""
    from stereovar.cli import main

    here = tmp_path_factory.mktemp("init")
    before = Path.cwd()
    os.chdir(here)
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            assert main(["init"]) == 0
    finally:
        os.chdir(before)
    files = {p.name: p.read_text(encoding="utf-8") for p in here.iterdir() if p.is_file()}
    assert set(files) == {"config.yaml", "audit.yaml"}, sorted(files)
    return files


def test_docs_pages_are_read_from_the_docs_sources():
    pages = docs_pages()
    assert {"configuration", "audit", "cluster", "getting-started", "generators"} <= pages
    assert page_of(DEFAULT_DOCS_URL + "nowhere.html") not in pages


@pytest.mark.parametrize("name", ["config.yaml", "audit.yaml"])
def test_starter_comments_point_to_docs_pages_not_repository_paths(starters, name):
    text = comments(starters[name])
    paths = sorted({m.group(0) for m in REPOSITORY_PATHS.finditer(text)})
    assert not paths, f"{name} sends a user to repository paths: {paths}"
    urls = [u.rstrip(".,;:") for u in URL.findall(text)]
    for url in urls:
        page = page_of(url)
        assert page is not None, f"{name}: {url} is not an address of the documentation"
        assert page == "" or page in docs_pages(), f"{name}: {url} names no page in docs/"
    if name == "config.yaml":
        assert len(urls) >= 4, f"{name}: expected the docs pages of its sections, got {urls}"
