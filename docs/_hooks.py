"""mkdocs hooks: a fence's marker is for the tests, a reader sees the language's highlighting.

A block fenced ```` ```python ros2 ```` runs elsewhere, or not at all
(``tests/snippets_support.py`` says which); Python-Markdown would not read such
a fence as code, so the marker is dropped before the page is rendered.
"""

from __future__ import annotations

import re
from typing import Any

MARKED_FENCE = re.compile(r"^(```[\w+-]+) [\w-]+$", flags=re.MULTILINE)


def on_page_markdown(markdown: str, **_: Any) -> str:
    """The page's Markdown with every fence's marker dropped."""
    return MARKED_FENCE.sub(r"\1", markdown)
