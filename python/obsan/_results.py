"""Typed results: each command's ``--json`` value as a frozen dataclass.

Every result keeps the whole JSON value: ``result["key"]`` and ``result.to_dict()``
give exactly what ``obsan ... --json`` prints (numeric lists as numpy arrays when numpy
is installed and ``obsan.NUMPY`` is true), so nothing the CLI says is lost; the typed
fields are what a program usually needs. Jupyter shows a result as a table
(``_repr_html_``) and formulas as LaTeX (``_repr_latex_``).
"""

from __future__ import annotations

import copy
import html
import re
import sys
from dataclasses import dataclass, field, fields
from typing import Any, Dict, Iterator, List, Mapping, NamedTuple, Optional, Tuple

def arrays(v: Any) -> Any:
    """Numeric lists (and rectangular lists of them) as numpy arrays, unless
    ``obsan.NUMPY`` is false or numpy is not installed."""
    pkg = sys.modules.get(__package__ or "obsan")
    if pkg is not None and not getattr(pkg, "NUMPY", True):
        return v
    try:
        import numpy as np
    except ImportError:
        return v
    return _convert(v, np)


def _convert(v: Any, np: Any) -> Any:
    if isinstance(v, dict):
        return {k: _convert(x, np) for k, x in v.items()}
    if isinstance(v, list):
        if v and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v):
            a = np.asarray(v)
            # Integers past int64 stay exact Python ints.
            return a if a.dtype != object else v
        items = [_convert(x, np) for x in v]
        if items and all(isinstance(x, np.ndarray) for x in items):
            if len({x.shape for x in items}) == 1 and len({x.dtype.kind for x in items}) == 1:
                return np.stack(items)
        return items
    return v


class Estimate(NamedTuple):
    """A value with its standard deviation (``None`` where none is defined) and unit
    (``""`` for a pure number)."""

    value: float
    sd: Optional[float]
    unit: str = ""


@dataclass(frozen=True, repr=False, eq=False)
class Result(Mapping[str, Any]):
    """A command's ``--json`` value: a read-only mapping of its keys, with typed fields."""

    raw: Dict[str, Any] = field(compare=False)

    def __getitem__(self, key: str) -> Any:
        return arrays(self.raw[key])

    def __iter__(self) -> Iterator[str]:
        return iter(self.raw)

    def __len__(self) -> int:
        return len(self.raw)

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Result):
            return type(self) is type(other) and self.raw == other.raw
        if isinstance(other, Mapping):
            return self.raw == dict(other)
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]

    def to_dict(self) -> Dict[str, Any]:
        """The ``--json`` value as plain Python data (lists, not arrays): a deep copy."""
        return copy.deepcopy(self.raw)

    def _summary(self) -> List[Tuple[str, Any]]:
        return [(f.name, getattr(self, f.name)) for f in fields(self) if f.name != "raw"]

    def __repr__(self) -> str:
        items = ", ".join(f"{k}={_short(v)}" for k, v in self._summary())
        return f"{type(self).__name__}({items})"

    def _repr_html_(self) -> str:
        rows = "".join(
            f"<tr><th style='text-align:left'>{html.escape(k)}</th>"
            f"<td style='text-align:left'>{html.escape(_short(v, 400))}</td></tr>"
            for k, v in self._summary()
        )
        return f"<table><caption>obsan {type(self).__name__}</caption>{rows}</table>"


def _short(v: Any, limit: int = 120) -> str:
    s = repr(v)
    return s if len(s) <= limit else s[: limit - 3] + "..."


def _latex_rows(rows: List[str]) -> str:
    return "$\\begin{aligned}" + " \\\\ ".join(rows) + "\\end{aligned}$"


@dataclass(frozen=True, repr=False, eq=False)
class SystemInfo(Result):
    """``obsan show``: the input-affine normal form of a system."""

    system: str
    states: List[str]
    params: List[str]
    inputs: List[str]
    outputs: Dict[str, str]
    restriction: Optional[str]

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "SystemInfo":
        return cls(
            raw=raw,
            system=raw["system"],
            states=list(raw["states"]),
            params=list(raw["params"]),
            inputs=list(raw["inputs"]),
            outputs={k: v["text"] for k, v in raw["outputs"].items()},
            restriction=raw.get("restriction"),
        )

    def _repr_latex_(self) -> str:
        rows = []
        for s in self.states:
            terms = [self.raw["f0"].get(s, {}).get("latex", "0")]
            for u, f in self.raw["fields"].items():
                t = f.get(s, {}).get("latex", "0")
                if t != "0":
                    terms.append(f"\\left({t}\\right) {u}")
            rhs = " + ".join(t for t in terms if t != "0") or "0"
            rows.append(f"\\dot{{{s}}} &= {rhs}")
        rows += [f"{k} &= {v['latex']}" for k, v in self.raw["outputs"].items()]
        return _latex_rows(rows)


@dataclass(frozen=True, repr=False, eq=False)
class Rank(Result):
    """``obsan rank``: the observability rank condition (one experiment, several, or
    with known initial values). ``exact`` is true when the rank is proven; otherwise
    ``error_bound`` bounds the probability that the true rank is higher."""

    system: str
    n: int
    rank: int
    variables: List[str]
    observable: List[str]
    unobservable: List[str]
    weakly_locally_observable: bool
    exact: bool
    error_bound: Optional[float]

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "Rank":
        return cls(
            raw=raw,
            system=raw.get("system", ""),
            n=int(raw.get("n", 0)),
            rank=int(raw.get("rank", 0)),
            variables=list(raw.get("state") or []),
            observable=list(raw.get("observable_variables") or []),
            unobservable=list(raw.get("unobservable_variables") or []),
            weakly_locally_observable=bool(raw.get("weakly_locally_observable", False)),
            exact=bool(raw.get("exact", False)),
            error_bound=raw.get("error_bound"),
        )


@dataclass(frozen=True, repr=False, eq=False)
class Symmetries(Result):
    """``obsan symmetries``: a basis of the continuous symmetries, each a vector
    (variable -> component as text), plus ``free``: the variables no output reaches,
    each direction d/dx a symmetry too; ``certificate`` is what it rests on
    (``closure`` exact, ``random`` with ``certification["error_bound"]``)."""

    system: str
    rank: int
    variables: List[str]
    vectors: List[Dict[str, str]]
    free: List[str]
    exact: bool
    certificate: str

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "Symmetries":
        return cls(
            raw=raw,
            system=raw.get("system", ""),
            rank=int(raw.get("rank", 0)),
            variables=list(raw.get("state") or []),
            vectors=[{k: c["text"] for k, c in w.items()} for w in raw.get("symmetries") or []],
            free=list(raw.get("free_directions") or []),
            exact=bool(raw.get("exact", False)),
            certificate=str(raw.get("certificate", "")),
        )

    def _repr_latex_(self) -> str:
        rows = []
        for i, w in enumerate(self.raw.get("symmetries") or [], 1):
            comps = " \\\\ ".join(w[x]["latex"] for x in self.variables if x in w)
            rows.append(f"w_{{{i}}} &= \\begin{{pmatrix}} {comps} \\end{{pmatrix}}")
        return _latex_rows(rows or ["\\text{no continuous symmetry}"])


@dataclass(frozen=True, repr=False, eq=False)
class Modes(Result):
    """``obsan modes``: the observable modes and the reduced system. ``closed`` is true
    when the reduced dynamics were found in the modes (then ``reduced_sys`` is its
    ``.sys`` text, full rank by construction)."""

    system: str
    rank: int
    full_rank: bool
    modes: List[str]
    closed: bool
    reduced_sys: Optional[str]

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "Modes":
        reduced = raw.get("reduced") or {}
        return cls(
            raw=raw,
            system=raw.get("system", ""),
            rank=int(raw.get("rank", 0)),
            full_rank=bool(raw.get("full_rank", False)),
            modes=[m["expr"] for m in raw.get("modes") or []],
            closed=bool(reduced.get("closed", False)),
            reduced_sys=raw.get("sys"),
        )


class Identifiability(NamedTuple):
    """One variable's global verdict: ``global``, ``local`` (with ``values`` > 1
    values giving the same output) or ``none`` (not identifiable)."""

    name: str
    kind: str
    verdict: str
    values: Optional[int]


@dataclass(frozen=True, repr=False, eq=False)
class Global(Result):
    """``obsan global``: per variable global / local with k values / not identifiable,
    the joint count of solutions and the discrete symmetries as maps."""

    system: str
    variables: List[Identifiability]
    solutions: Optional[int]
    maps: List[Any]

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "Global":
        return cls(
            raw=raw,
            system=raw.get("system", ""),
            variables=[
                Identifiability(v.get("name", ""), v.get("kind", ""), v.get("verdict", ""), v.get("values"))
                for v in raw.get("variables") or []
            ],
            solutions=raw.get("solutions"),
            maps=list(raw.get("maps") or []),
        )


class LieDerivative(NamedTuple):
    name: str
    order: int
    text: str
    latex: str


@dataclass(frozen=True, repr=False, eq=False)
class LieDerivatives(Result):
    """``obsan lie``: the Lie derivatives of the outputs, in canonical form."""

    system: str
    derivatives: List[LieDerivative]

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "LieDerivatives":
        items = [
            LieDerivative(d["lie_derivative"], int(d["order"]), d["text"], d["latex"])
            for d in raw.get("lie_derivatives") or []
        ]
        return cls(raw=raw, system=raw.get("system", ""), derivatives=items)

    def _repr_latex_(self) -> str:
        return _latex_rows([f"{_latex_name(d.name)} &= {d.latex}" for d in self.derivatives])


def _latex_name(name: str) -> str:
    return re.sub(r"L_(\w+)", r"L_{\1}", name).replace(" ", "\\,")


@dataclass(frozen=True, repr=False, eq=False)
class Check(Result):
    """``obsan check``: candidate observable modes against eq. (11)."""

    system: str
    modes: Dict[str, bool]
    complete: bool
    exact: bool

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "Check":
        return cls(
            raw=raw,
            system=raw.get("system", ""),
            modes={c["mode"]: bool(c["observable_mode"]) for c in raw.get("checks") or []},
            complete=bool(raw.get("complete", False)),
            exact=bool(raw.get("exact", False)),
        )


@dataclass(frozen=True, repr=False, eq=False)
class Design(Result):
    """``obsan design``: with candidate sensors, ``sets`` are the minimal sets of
    candidates (by count, then cost) that make the target observable; the input families'
    verdicts are in ``result["inputs"]``."""

    system: str
    sets: List[List[str]]

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "Design":
        sensors = raw.get("sensors") or {}
        sets = [list(x.get("candidates") or []) for x in sensors.get("sets") or []]
        return cls(raw=raw, system=str(raw.get("system", "")), sets=sets)


@dataclass(frozen=True, repr=False, eq=False)
class Expression(Result):
    """``obsan simplify`` / ``obsan diff``: the exact canonical form. ``is_zero`` is
    ``None`` where the engine could not decide (``decided`` false): the form is
    nonzero but holds atoms that may be related, listed in ``undecided_atoms``."""

    input: str
    canonical: str
    latex: str
    is_zero: Optional[bool]
    decided: bool
    undecided_atoms: List[str]
    exact: bool

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "Expression":
        return cls(
            raw=raw,
            input=raw.get("input", ""),
            canonical=raw.get("canonical", ""),
            latex=raw.get("latex", ""),
            is_zero=raw.get("is_zero"),
            decided=bool(raw.get("decided", raw.get("is_zero") is not None)),
            undecided_atoms=[str(a) for a in raw.get("undecided_atoms", [])],
            exact=bool(raw.get("exact", False)),
        )

    def __str__(self) -> str:
        return self.canonical

    def _repr_latex_(self) -> str:
        return f"${self.latex}$"


@dataclass(frozen=True, repr=False, eq=False)
class Verification(Result):
    """``obsan verify``: a decomposition file's exact checks (a failed check is a value)."""

    system: str
    passed: bool
    checks: List[Tuple[str, bool]]
    certificate: str

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "Verification":
        return cls(
            raw=raw,
            system=raw.get("system", ""),
            passed=bool(raw.get("pass", False)),
            checks=[(c["check"], bool(c["pass"])) for c in raw.get("checks") or []],
            certificate=str(raw.get("certificate", "")),
        )


_UNIT = re.compile(r"^(.*?) \((.*)\)$")


def _split_unit(key: str) -> Tuple[str, str]:
    m = _UNIT.match(key)
    return (m.group(1), m.group(2)) if m else (key, "")


def _estimates(d: Optional[Mapping[str, Any]]) -> Dict[str, Estimate]:
    out: Dict[str, Estimate] = {}
    for key, v in (d or {}).items():
        name, unit = _split_unit(key)
        out[name] = Estimate(v["value"], v.get("sd"), unit)
    return out


@dataclass(frozen=True, repr=False, eq=False)
class Calibration(Result):
    """``obsan calibrate``: the paper's calibration parameters (15) and, with ``d0``, the
    metric ones (rho, r_right, r_left, B), each an :class:`Estimate`."""

    method: str
    params: Dict[str, Estimate]
    metric: Dict[str, Estimate]
    sigma_beta: Optional[float]

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "Calibration":
        return cls(
            raw=raw,
            method=raw.get("method", ""),
            params=_estimates(raw.get("params")),
            metric=_estimates(raw.get("metric")),
            sigma_beta=raw.get("sigma_beta"),
        )


@dataclass(frozen=True, repr=False, eq=False)
class CramerRao(Result):
    """``obsan crlb``: the Cramér–Rao bound on each parameter's sd, by name, in
    ``units`` (``deg`` for angles, ``%`` for relative ones)."""

    sd: Dict[str, float]
    sd_with_encoder_noise: Dict[str, float]
    units: Dict[str, str]

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "CramerRao":
        sd: Dict[str, float] = {}
        units: Dict[str, str] = {}
        for key, v in (raw.get("crlb_sd") or {}).items():
            name, unit = _split_unit(key)
            sd[name], units[name] = v, unit
        enc = {_split_unit(k)[0]: v for k, v in (raw.get("crlb_sd_with_encoder_noise") or {}).items()}
        return cls(raw=raw, sd=sd, sd_with_encoder_noise=enc, units=units)


class NamedEffect(NamedTuple):
    """An effect ``diagnose`` named: its params as :class:`Estimate` s and its
    likelihood-ratio statistic."""

    effect: str
    origin: str
    estimates: Dict[str, Estimate]
    lr: float


@dataclass(frozen=True, repr=False, eq=False)
class Diagnosis(Result):
    """``obsan diagnose``: the named effects (in order), the final fit and the
    evidence; ``extended_sys`` is the model with them added."""

    model: str
    named: List[NamedEffect]
    params: Dict[str, Estimate]
    extended_sys: Optional[str]

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "Diagnosis":
        named = [
            NamedEffect(
                n.get("effect", ""),
                n.get("origin", ""),
                {e[0]: Estimate(e[1], e[2]) for e in n.get("estimates") or []},
                float(n.get("lr", 0.0)),
            )
            for n in raw.get("named") or []
        ]
        final = raw.get("final_fit") or {}
        params = {p[0]: Estimate(p[1], p[2]) for p in final.get("params") or []}
        return cls(
            raw=raw,
            model=str(raw.get("model", "")),
            named=named,
            params=params,
            extended_sys=raw.get("extended_sys"),
        )


@dataclass(frozen=True, repr=False, eq=False)
class MonteCarloTable(Result):
    """One of the paper's Tables IV–VII from ``obsan montecarlo`` (docs/montecarlo.md)."""

    table: Any
    title: str
    runs: int

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "MonteCarloTable":
        return cls(raw=raw, table=raw.get("table"), title=str(raw.get("title", "")), runs=int(raw.get("runs", 0)))
