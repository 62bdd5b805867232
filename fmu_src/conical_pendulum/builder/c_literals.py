"""C literals from Python values, written one way for every generated file, and the templates
they fill: a generated file is data (defines, tables) in a template with named holes
(builder/templates/*.in, string.Template's $holes); the logic that reads it is hand-written C
in runtime/csrc."""

from __future__ import annotations

import json
import math
from pathlib import Path
from string import Template

TEMPLATES = Path(__file__).parent / "templates"


def string(text: str) -> str:
    """A C string literal: a JSON string of ASCII text (non-ASCII escaped) is one."""
    return json.dumps(text)


def double(value: float) -> str:
    """A C double that reads back as the same double: Python's repr (the shortest that
    round-trips), INFINITY and -INFINITY from <math.h>."""
    value = float(value)
    if math.isinf(value):
        return "INFINITY" if value > 0 else "-INFINITY"
    if math.isnan(value):
        raise ValueError("a C literal of NaN: no variable starts undefined")
    return repr(value)


def define(name: str, value) -> str:
    """#define NAME value (value as it is: a number, or a literal made by this module)."""
    return f"#define {name} {value}"


def initializer(items) -> str:
    """{a, b, c} on one line."""
    return "{" + ", ".join(str(item) for item in items) + "}"


def rows(items, comments=None) -> str:
    """An initializer's rows, one a line, each a comment's (a name's) if given."""
    comments = comments if comments is not None else [None] * len(items)
    return "\n".join(
        f"    {item}," + (f"  /* {comment} */" if comment is not None else "")
        for item, comment in zip(items, comments)
    )


def fill(template: str, **holes) -> str:
    """builder/templates/<template> with its $holes filled (every one: a missing hole is an
    error, not an empty line)."""
    return Template((TEMPLATES / template).read_text()).substitute(holes)
