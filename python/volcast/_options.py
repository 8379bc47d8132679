"""Keyword arguments to `volcast render`'s and `volcast view`'s own options.

The option list comes from the command line's definition (``_volcast.render_options()``), so every option of
``volcast render`` is a keyword of ``volcast.render`` with the same values and defaults: ``--clip-plane 0,0,1``
is ``clip_plane=(0, 0, 1)``, ``--shadows`` is ``shadows=True``, ``--size 640x480`` is ``size=(640, 480)`` (or
``size=512`` for a square), ``--surface`` (repeatable) takes one value or a list of them.
"""

from __future__ import annotations

import numbers
import os
from typing import Any, Dict, List, Mapping, NamedTuple, Sequence

from . import _volcast


class Option(NamedTuple):
    """One option: its keyword, the command line's flag, its kind, help text, defaults and allowed values."""

    keyword: str
    flag: str
    kind: str  # "flag", "value", "values" (a fixed count, as dims) or "repeat" (one value or a list)
    help: str
    defaults: List[str]
    allowed: List[str]


_SPECS: Dict[str, Dict[str, Option]] = {}


def options(command: str = "render") -> Dict[str, Option]:
    """Every option of ``volcast render`` (or ``view``, or ``open``: how a file is read) as a keyword, by keyword."""
    if command not in _SPECS:
        listing = {"render": _volcast.render_options, "view": _volcast.view_options, "open": _volcast.open_options}[
            command
        ]()
        _SPECS[command] = {o[0]: Option(*o) for o in listing}
    return _SPECS[command]


def _text(keyword: str, value: Any) -> str:
    if isinstance(value, (str, os.PathLike)):
        return os.fspath(value)
    if isinstance(value, bool):
        raise TypeError(f"{keyword}= takes a value, not {value!r}")
    if isinstance(value, numbers.Integral):
        return f"{value}x{value}" if keyword == "size" else str(int(value))
    if isinstance(value, numbers.Real):
        return repr(float(value))
    if isinstance(value, Sequence) or hasattr(value, "__array__"):
        sep = "x" if keyword == "size" else ":" if keyword == "slice" else ","
        return sep.join(_text(keyword + "[]", v) for v in list(value))
    raise TypeError(f"{keyword}= does not take {type(value).__name__} values")


def argv(command: str, given: Mapping[str, Any]) -> List[str]:
    """The command line of ``volcast <command>`` that ``given`` (keywords, None meaning "not given") stands for."""
    spec = options(command)
    out: List[str] = []
    for keyword, value in given.items():
        if value is None:
            continue
        o = spec.get(keyword)
        if o is None:
            raise TypeError(
                f"{command}() got an unexpected keyword argument {keyword!r}; "
                f"volcast.options({command!r}) lists them"
            )
        if o.kind == "flag":
            if not isinstance(value, (bool, int)) or value not in (0, 1):
                raise TypeError(f"{keyword}= takes True or False, not {value!r}")
            if value:
                out.append(o.flag)
        elif o.kind == "values":
            out.append(o.flag)
            out.extend(_text(keyword, v) for v in value)
        elif o.kind == "repeat":
            for v in value if isinstance(value, list) else [value]:
                out.append(f"{o.flag}={_text(keyword, v)}")
        else:
            out.append(f"{o.flag}={_text(keyword, value)}")
    return out
