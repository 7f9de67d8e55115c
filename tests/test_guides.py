"""The docs site's code runs: every Python block of every page, as a user would run it.

A block that does not run here says why in its fence (`snippets_support.MARKERS`,
`snippets_support.NOT_PROGRAMS`); a block of any other kind fails the check, so
that no page can hold code that nothing runs.
"""

from __future__ import annotations

import importlib
import re
import runpy
from pathlib import Path

import pytest

import pyrobots_aio
import snippets_support
from snippets_support import (
    GUIDES,
    MARKERS,
    NOT_PROGRAMS,
    RUN_ELSEWHERE,
    Block,
    all_blocks,
    guides,
    run_snippet,
)
from test_exports import EXPORTS

BLOCKS = [block for page in guides() for block in all_blocks(page)]
PROGRAMS = [block for block in BLOCKS if (block.language, block.marker) == ("python", "")]
# the snippets run in a project with the pytest config that the testing guide gives
(CONFIG,) = snippets_support.blocks(GUIDES / "guides" / "testing.md", "toml")


def test_every_block_runs_here_or_says_why_not() -> None:
    assert len(PROGRAMS) >= 20
    unexplained = [
        block.where
        for block in BLOCKS
        if block not in PROGRAMS
        and not (block.language == "python" and block.marker in MARKERS)
        and not (block.language in NOT_PROGRAMS and not block.marker)
    ]
    assert unexplained == []


def test_each_guide_has_code_that_runs() -> None:
    runs = [block for block in BLOCKS if block in PROGRAMS or block.marker in RUN_ELSEWHERE]
    pages = {block.document.name for block in runs if block.document.parent.name == "guides"}
    assert pages == {page.name for page in (GUIDES / "guides").glob("*.md")}


def test_the_site_renders_a_marked_block_as_code() -> None:
    # Python-Markdown reads a fence with a word after its language as prose: the hook drops it
    render = runpy.run_path(str(GUIDES / "_hooks.py"))["on_page_markdown"]
    page = "Beside a sim-node:\n\n```python ros2\nimport rclpy\n```\n"
    assert render(page) == "Beside a sim-node:\n\n```python\nimport rclpy\n```\n"


@pytest.mark.parametrize("block", PROGRAMS, ids=[block.where for block in PROGRAMS])
def test_the_block_runs(block: Block, tmp_path: Path) -> None:
    done = run_snippet(block.code, tmp_path, CONFIG, f"block_{block.line}")
    assert done.returncode == 0, done.stdout + done.stderr


def _documented(target: str) -> set[str]:
    """The names a ``::: target`` documents: a namespace's ``__all__``, or the one it names."""
    try:
        namespace = importlib.import_module(target)
    except ModuleNotFoundError:
        return {target.rpartition(".")[2]}
    return set(namespace.__all__)


def _targets() -> set[str]:
    """What the API reference's pages document, a ``::: target`` each (a namespace or a name)."""
    pages = (GUIDES / "reference").glob("*.md")
    return {
        target
        for page in pages
        for target in re.findall(r"^::: (pyrobots_aio[\w.]*)$", page.read_text(), re.MULTILINE)
    }


def _reference() -> set[str]:
    """Every name the API reference's pages document (the top page's own are listed by name)."""
    return {name for target in _targets() - {"pyrobots_aio"} for name in _documented(target)}


def test_the_reference_documents_every_public_name() -> None:
    unexplained_alias = {"ActionCancelled"}  # asyncio.CancelledError: the page says so in words
    assert set(pyrobots_aio.__all__) - unexplained_alias <= _reference()


def test_the_reference_has_a_page_for_every_public_namespace() -> None:
    assert set(EXPORTS) - {"pyrobots_aio"} <= _targets()
