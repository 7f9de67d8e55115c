"""The JSON the library writes (recordings, Foxglove channels): strict, whatever the values.

Strict JSON has no NaN nor Infinity: `strict_json` writes them as null
(`null_nonfinite`), and what ``json`` cannot encode at all (numpy values,
sets, anything else) as `jsonable` makes it.
"""

from __future__ import annotations

import json
import math


def jsonable(value: object) -> object:
    """Make what ``json`` cannot encode encodable: numpy values, sets, anything else by repr."""
    tolist = getattr(value, "tolist", None)  # numpy arrays and scalars
    if callable(tolist):
        return tolist()
    if isinstance(value, set | frozenset | tuple):
        return list(value)
    return repr(value)


def null_nonfinite(value: object) -> object:
    """``value`` with each non-finite float (NaN, Infinity) replaced by None, for strict JSON."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if value is None or isinstance(value, str | int):
        return value
    if isinstance(value, dict):
        return {
            repr(k) if isinstance(k, float) and not math.isfinite(k) else k: null_nonfinite(v)
            for k, v in value.items()
        }
    if isinstance(value, list | tuple):
        return [null_nonfinite(v) for v in value]
    return null_nonfinite(jsonable(value))


def strict_json(value: object) -> bytes:
    """Compact strict JSON, as UTF-8 (NaN and Infinity become null)."""
    try:
        text = json.dumps(value, separators=(",", ":"), allow_nan=False, default=jsonable)
    except ValueError:  # "Out of range float values are not JSON compliant"
        text = json.dumps(null_nonfinite(value), separators=(",", ":"), default=jsonable)
    return text.encode()
