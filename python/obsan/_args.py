"""Python values as the CLI's arguments: texts, paths and numbers, checked before
anything runs (a wrong type is a TypeError, a missing input file FileNotFoundError)."""

from __future__ import annotations

import errno
import numbers
import os
from typing import Any, Iterable, List, Mapping, Optional, Sequence, Union

PathLike = Union[str, "os.PathLike[str]"]
#: A number the CLI reads exactly: an int, a float (its shortest repr: 0.9 is 9/10)
#: or a ``fractions.Fraction`` (``p/q``).
Number = Union[int, float, numbers.Rational]


def arg(a: Any) -> str:
    """An argument as text: a str, a path or a number; anything else (None, bytes,
    a list) is a TypeError before anything runs (``str(None)`` would be the
    folder ``./None``)."""
    if isinstance(a, str):
        return a
    if isinstance(a, os.PathLike):
        p = os.fspath(a)
        if not isinstance(p, str):
            raise TypeError(f"expected a str path, not {type(p).__name__}")
        return p
    if isinstance(a, numbers.Real):
        return value(a)
    raise TypeError(f"expected a str, a path or a number, not {type(a).__name__}")


def text(what: str, a: Any) -> str:
    """A text argument (an expression, a symbol, a method): a str, else TypeError."""
    if not isinstance(a, str):
        raise TypeError(f"{what} must be a str, not {type(a).__name__}")
    return a


def path(what: str, a: Any) -> str:
    """A path argument: a str or os.PathLike, else TypeError."""
    if not isinstance(a, (str, os.PathLike)):
        raise TypeError(f"{what} must be a path (str or os.PathLike), not {type(a).__name__}")
    return arg(a)


def existing(what: str, a: Any) -> str:
    """A path the command reads: it must exist (FileNotFoundError, as ``open`` raises)."""
    p = path(what, a)
    if not os.path.exists(p):
        raise FileNotFoundError(errno.ENOENT, f"{what}: no such file or directory", p)
    return p


def value(x: Any) -> str:
    """A value as the CLI reads it; a float keeps its shortest repr (0.9 is 9/10)."""
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, float):
        return repr(x)
    if isinstance(x, numbers.Integral):
        return str(int(x))
    if isinstance(x, numbers.Rational):
        return str(x)  # a Fraction stays exact: 9/10
    if isinstance(x, numbers.Real):
        return repr(float(x))
    return arg(x)


def integer(what: str, x: Any) -> str:
    """A count or a seed: an int (not a bool, not a float), else TypeError."""
    if isinstance(x, bool) or not isinstance(x, numbers.Integral):
        raise TypeError(f"{what} must be an int, not {type(x).__name__}")
    return str(int(x))


def is_array(v: Any) -> bool:
    return hasattr(v, "tolist") and hasattr(v, "shape")


class Flags:
    """The argument list of one command, built flag by flag: each method checks its
    value's type, so a wrong one is a TypeError naming the keyword."""

    def __init__(self, *head: str) -> None:
        self.argv: List[str] = list(head)

    def text(self, flag: str, v: Optional[str]) -> "Flags":
        if v is not None:
            self.argv += [flag, text(_kw(flag), v)]
        return self

    def texts(self, flag: str, vs: Union[str, Iterable[str], None]) -> "Flags":
        """A repeated flag; a single str is one item."""
        if vs is None:
            return self
        for v in [vs] if isinstance(vs, str) else list(vs):
            self.argv += [flag, text(_kw(flag), v)]
        return self

    def path(self, flag: str, v: Optional[PathLike]) -> "Flags":
        if v is not None:
            self.argv += [flag, path(_kw(flag), v)]
        return self

    def number(self, flag: str, v: Optional[Number]) -> "Flags":
        if v is not None:
            if isinstance(v, bool) or not isinstance(v, numbers.Real):
                raise TypeError(f"{_kw(flag)} must be a number, not {type(v).__name__}")
            self.argv += [flag, value(v)]
        return self

    def integer(self, flag: str, v: Optional[int]) -> "Flags":
        if v is not None:
            self.argv += [flag, integer(_kw(flag), v)]
        return self

    def switch(self, flag: str, on: bool) -> "Flags":
        if not isinstance(on, bool):
            raise TypeError(f"{_kw(flag)} must be a bool, not {type(on).__name__}")
        if on:
            self.argv.append(flag)
        return self

    def pairs(self, flag: str, m: Optional[Mapping[str, Any]]) -> "Flags":
        """``{"q": 0.9}`` as ``--set q=0.9`` (one flag a pair)."""
        if m is None:
            return self
        if not isinstance(m, Mapping):
            raise TypeError(f"{_kw(flag)} must be a mapping (dict), not {type(m).__name__}")
        for k, x in m.items():
            self.argv += [flag, f"{text(_kw(flag) + ' key', k)}={value(x)}"]
        return self

    def numbers(
        self, flag: str, vs: Union[Number, Sequence[Number], Any, None], key: Optional[str] = None
    ) -> "Flags":
        """One comma-joined list; with ``key``, as ``flag key=LIST`` (``q=[0.9, 0, -1]`` is
        ``--set q=0.9,0,-1``)."""
        if vs is None:
            return self
        name = key if key is not None else _kw(flag)
        items: Any = getattr(vs, "tolist")() if is_array(vs) else vs
        if isinstance(items, numbers.Real):
            items = [items]
        if not isinstance(items, (list, tuple)):
            raise TypeError(f"{name} must be a number or a list of numbers")
        joined = ",".join(value(x) for x in items)
        self.argv += [flag, joined if key is None else f"{key}={joined}"]
        return self


def _kw(flag: str) -> str:
    return flag.lstrip("-").replace("-", "_")
