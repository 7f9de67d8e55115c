"""Checking an output path before any work starts, so a typo costs no run."""

from __future__ import annotations

import os
from pathlib import Path

from pyrobots_aio.recording import shown


def unwritable(option: str, path: str, example: str) -> str | None:
    """Why ``path``, given to ``option``, cannot be written as a file, in words; None if it can.

    ``example`` is a file name suggested inside ``path`` when it is a directory.

    Examples:
        >>> print(unwritable("--record", "no/x.jsonl", "walk.jsonl"))
        --record no/x.jsonl: the directory no does not exist: create it first, or choose another
    """
    file = Path(path)
    parent = file.parent
    if file.is_dir():
        return f"{option} {shown(path)} is a directory: name a file, e.g. {shown(file / example)}"
    if not parent.exists():
        return (
            f"{option} {shown(path)}: the directory {shown(parent)} does not exist: "
            "create it first, or choose another"
        )
    if not parent.is_dir():
        return f"{option} {shown(path)}: {shown(parent)} is not a directory"
    if file.exists() and not os.access(file, os.W_OK):
        return f"{option} {shown(path)}: the file may not be overwritten (permission denied)"
    if not file.exists() and not os.access(parent, os.W_OK | os.X_OK):
        return (
            f"{option} {shown(path)}: the directory {shown(parent)} may not be written "
            "(permission denied): choose another"
        )
    return None
