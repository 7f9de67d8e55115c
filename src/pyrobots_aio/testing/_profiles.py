"""The exploration profiles' names, and how a run picks one (no Hypothesis needed here).

- ``ci``: derandomized, the same examples at every run (no example database);
- ``dev``: random examples; a failing one is saved in Hypothesis's example
  database (``.hypothesis/``) and tried first at the next run;
- ``long``: ``dev`` with ten times the examples, for a long local search.
"""

from __future__ import annotations

import os

PROFILES = ("ci", "dev", "long")
"""The exploration profiles, by name: ``profile=`` and ``--explore-profile`` take one of these."""
DEFAULT_PROFILE = "ci"
"""Deterministic unless asked otherwise: a test suite gives the same verdict at every run."""
ENVIRONMENT = "PYROBOTS_AIO_EXPLORE"
"""The environment variable that chooses the profile when the code and pytest do not."""


def chosen_profile(profile: str | None) -> str:
    """``profile``, else the environment's, else `DEFAULT_PROFILE`.

    Raises:
        ValueError: Not one of `PROFILES`.
    """
    name = profile or os.environ.get(ENVIRONMENT) or DEFAULT_PROFILE
    if name not in PROFILES:
        msg = f"the explore profile must be one of {list(PROFILES)}, got {name!r}"
        raise ValueError(msg)
    return name
