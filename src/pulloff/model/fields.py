"""Field types and problem lines shared by every model kind.

A problem is one line naming the dotted key, the value as written and the reason, e.g.
``material.G = -1.0: must be >= 0 (shear modulus, Pa)``. Section-level checks raise
:func:`bad_line` with ``{p}`` standing for the section's dotted prefix.
"""

from __future__ import annotations

import math
import numbers
import re
from typing import Annotated, Any

from pydantic import BeforeValidator
from pydantic_core import PydanticCustomError


def bad(reason: str) -> PydanticCustomError:
    """A problem with one value: the key and value are added by the formatter."""
    return PydanticCustomError("scene", "{reason}", {"reason": reason})


def bad_line(line: str) -> PydanticCustomError:
    """A whole problem line for a section-level check; "{p}" stands for the section's prefix
    (with its dot: ``{p}G`` reads ``material.G``) and "{k}" for the section's own key."""
    return PydanticCustomError("scene", "{line}", {"line": line})


def _to_float(v: Any) -> float:
    # bool is an int subclass: without this check `G: true` would silently become 1.0
    if isinstance(v, bool):
        raise bad("must be a number, not a boolean")
    if isinstance(v, numbers.Real):
        try:
            f = float(v)
        except OverflowError:
            raise bad("too large for a float") from None
    elif isinstance(v, str):
        try:
            f = float(v.strip())
        except ValueError:
            raise bad("must be a number") from None
    else:
        raise bad(f"must be a number, not a {type(v).__name__}")
    if not math.isfinite(f):
        raise bad("must be finite")
    return f


def _to_int(v: Any) -> int:
    f = _to_float(v)
    if not f.is_integer():
        raise bad("must be an integer")
    return int(f)


def _no_bool(v: Any) -> Any:
    if isinstance(v, bool):
        raise bad("must be 1, not a boolean")
    return v


Num = Annotated[float, BeforeValidator(_to_float)]
Int = Annotated[int, BeforeValidator(_to_int)]
NoBool = BeforeValidator(_no_bool)


def fmt(x: Any) -> str:
    """Short, exact text for a value: 6e6 rather than 6000000.0, 1e-8 rather than 1e-08."""
    if isinstance(x, bool) or x is None:
        return {True: "true", False: "false", None: "null"}[x]
    if isinstance(x, float) and math.isfinite(x) and x != 0:
        tidy = lambda t: re.sub(r"e\+?(-?)0*(\d)", r"e\1\2", t)  # noqa: E731
        digits = re.sub(r"e.*|[-.]", "", repr(x)).strip("0")
        sci, pos = tidy(f"{x:.{max(len(digits) - 1, 0)}e}"), tidy(repr(x))
        return sci if float(sci) == x and len(sci) < len(pos) else pos
    s = repr(x)
    return s if len(s) <= 80 else s[:77] + "..."
