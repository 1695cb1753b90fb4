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
import math
import operator
import re
import sys
from dataclasses import dataclass, field, fields
from typing import Any, Callable, Dict, Iterator, List, Mapping, NamedTuple, Optional, Tuple

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
    ``error_bound`` bounds the probability that the true rank is higher. With unknown
    inputs (docs/engine.md): ``observable`` lists names (``orders`` gives the output
    derivative order from which each is observable), ``unknown_inputs`` the model's, and
    ``reconstructable`` each reconstructable input with its order."""

    system: str
    n: int
    rank: int
    variables: List[str]
    observable: List[str]
    unobservable: List[str]
    weakly_locally_observable: bool
    exact: bool
    error_bound: Optional[float]
    unknown_inputs: List[str] = field(default_factory=list)
    orders: Dict[str, int] = field(default_factory=dict)
    reconstructable: Dict[str, int] = field(default_factory=dict)

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "Rank":
        obs = list(raw.get("observable_variables") or [])
        # With unknown inputs each entry is {name, order}.
        orders = {str(o["name"]): int(o["order"]) for o in obs if isinstance(o, dict)}
        rec = raw.get("reconstructable_inputs") or []
        return cls(
            raw=raw,
            system=raw.get("system", ""),
            n=int(raw.get("n", 0)),
            rank=int(raw.get("rank", 0)),
            variables=list(raw.get("state") or []),
            observable=[str(o["name"]) if isinstance(o, dict) else o for o in obs],
            unobservable=list(raw.get("unobservable_variables") or []),
            weakly_locally_observable=bool(raw.get("weakly_locally_observable", False)),
            exact=bool(raw.get("exact", False)),
            error_bound=raw.get("error_bound"),
            unknown_inputs=list(raw.get("unknown_inputs") or []),
            orders=orders,
            reconstructable={str(o["name"]): int(o["order"]) for o in rec},
        )


@dataclass(frozen=True, repr=False, eq=False)
class Symmetries(Result):
    """``obsan symmetries``: a basis of the continuous symmetries, each a vector
    (variable -> component as text), plus ``free``: the variables no output reaches,
    each direction d/dx a symmetry too; ``certificate`` is what it rests on
    (``closure``, ``invariance`` and ``span`` exact, ``random`` with
    ``certification["error_bound"]``). With unknown
    inputs: the kernel of the observable codistribution, ``certificate``
    ``unknown_input_invariance`` (exact; docs/engine.md). ``decided`` false: the
    atoms in ``undecided_atoms`` may be related, so each vector is still proven to
    annihilate the codistribution but the rank is an upper bound and there may be
    more symmetries (``exact`` is then false)."""

    system: str
    rank: int
    variables: List[str]
    vectors: List[Dict[str, str]]
    free: List[str]
    exact: bool
    certificate: str
    decided: bool = True
    undecided_atoms: List[str] = field(default_factory=list)

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
            decided=bool(raw.get("decided", True)),
            undecided_atoms=[str(a) for a in raw.get("undecided_atoms") or []],
        )

    def _repr_latex_(self) -> str:
        rows = []
        for i, w in enumerate(self.raw.get("symmetries") or [], 1):
            comps = " \\\\ ".join(w[x]["latex"] for x in self.variables if x in w)
            rows.append(f"w_{{{i}}} &= \\begin{{pmatrix}} {comps} \\end{{pmatrix}}")
        return _latex_rows(rows or ["\\text{no continuous symmetry}"])


class ReducedUnknownInput(NamedTuple):
    """An unknown input of a reduced system (``obsan modes`` with unknown inputs): the
    model's ``input`` itself (``factor`` ``None``, reconstructable from output derivatives
    of ``order``), or the combination ``factor * input + offset`` named ``name``, recovered
    from the first derivative of ``mode`` (``order`` ``None``)."""

    name: str
    input: str
    factor: Optional[str]
    offset: Optional[str]
    mode: str
    order: Optional[int]


@dataclass(frozen=True, repr=False, eq=False)
class Modes(Result):
    """``obsan modes``: the observable modes and the reduced system. ``closed`` is true
    when the reduced dynamics were found in the modes (then ``reduced_sys`` is its
    ``.sys`` text, full rank by construction). ``decided`` false: the atoms in
    ``undecided_atoms`` may be related, so the rank is an upper bound (``full_rank``
    is then ``None`` at formal full rank): the modes' eq. (11) residuals and the
    reduced system's substitutions are proven, their completeness is not. With unknown
    inputs, ``unknown_inputs`` are the model's and ``reduced_inputs`` those (or their
    combinations) the reduced system is driven by; at full rank ``modes`` are the
    variables and ``closed`` is true (the reduced system is the model)."""

    system: str
    rank: int
    full_rank: Optional[bool]
    modes: List[str]
    closed: bool
    reduced_sys: Optional[str]
    decided: bool = True
    undecided_atoms: List[str] = field(default_factory=list)
    unknown_inputs: List[str] = field(default_factory=list)
    reduced_inputs: List[ReducedUnknownInput] = field(default_factory=list)

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "Modes":
        reduced = raw.get("reduced") or {}
        unknown = "unknown_inputs" in raw
        full = unknown and bool(raw.get("full_rank"))
        return cls(
            raw=raw,
            system=raw.get("system", ""),
            rank=int(raw.get("rank", 0)),
            full_rank=None if raw.get("full_rank") is None else bool(raw["full_rank"]),
            modes=[m["expr"] for m in raw.get("modes") or []],
            closed=full or bool(reduced.get("closed", False)),
            reduced_sys=raw.get("sys"),
            decided=bool(raw.get("decided", True)),
            undecided_atoms=[str(a) for a in raw.get("undecided_atoms") or []],
            unknown_inputs=[str(w) for w in raw.get("unknown_inputs") or []],
            reduced_inputs=[
                ReducedUnknownInput(
                    name=str(i["name"]),
                    input=str(i["input"]),
                    factor=i.get("factor"),
                    offset=i.get("offset"),
                    mode=str(i["mode"]),
                    order=None if i.get("order") is None else int(i["order"]),
                )
                for i in raw.get("reduced_inputs") or []
            ],
        )


class Identifiability(NamedTuple):
    """One variable's global verdict: ``global``, ``local`` (with ``values`` > 1
    values giving the same output) or ``none`` (not identifiable)."""

    name: str
    kind: str
    verdict: str
    values: Optional[int]
    angle: bool = False
    """An angle entering only through sin/cos, counted modulo 2 pi."""
    at_most: bool = False
    """``values`` is an upper bound: an angle output was read through its tangent
    (modulo pi) and the symmetries found do not settle the count."""


class MapImage(NamedTuple):
    """One moved variable of a discrete map: ``var -> sign * image``, plus pi
    when ``plus_pi`` (angles: ``theta -> phi + pi`` or ``pi - phi``). ``image``
    is a variable, or (the input-output route's rational maps) a formula in
    the variables with ``+ - * / ^`` and integers, e.g. ``(a*g - b)/g``."""

    var: str
    image: str
    sign: int
    plus_pi: bool


def _evaluate(formula: str, values: Mapping[str, float]) -> float:
    """A map image's value at a point: a variable, or an arithmetic formula
    in the variables (``+ - * / ^``, integers, parentheses) read with Python's
    own parser and nothing but those operations evaluated."""
    import ast

    ops: Dict[type, Callable[[float, float], float]] = {
        ast.Add: operator.add,
        ast.Sub: operator.sub,
        ast.Mult: operator.mul,
        ast.Div: operator.truediv,
        ast.Pow: operator.pow,
    }

    def ev(node: ast.AST) -> float:
        if isinstance(node, ast.Expression):
            return ev(node.body)
        if isinstance(node, ast.BinOp) and type(node.op) in ops:
            return ops[type(node.op)](ev(node.left), ev(node.right))
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            v = ev(node.operand)
            return -v if isinstance(node.op, ast.USub) else v
        if isinstance(node, ast.Name):
            return float(values[node.id])
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)):
            return float(node.value)
        raise ValueError(f"not a map image: {formula!r}")

    return ev(ast.parse(formula.replace("^", "**"), mode="eval"))


class DiscreteMap(NamedTuple):
    """An exact discrete symmetry of ``obsan global`` (``text`` as printed, e.g.
    ``(x, theta) -> (-x, pi - theta)``) with its moved variables."""

    text: str
    images: List[MapImage]

    @classmethod
    def parse(cls, text: str) -> "DiscreteMap":
        """Reads the printed form: ``a -> b`` or ``(a, b) -> (c, d)``, each image
        ``v``, ``-v``, ``v + pi`` or ``pi - v``."""
        lhs, sep, rhs = text.partition(" -> ")
        if not sep:
            raise ValueError(f"not a map: {text!r}")
        lhs, rhs = lhs.strip(), rhs.strip()
        # Several variables: one pair of parentheses around each side, the
        # images split at the commas outside the formulas' own parentheses.
        if lhs.startswith("("):
            lhs, rhs = lhs[1:-1], rhs[1:-1]
        names = lhs.split(", ")
        targets, depth, cur = [], 0, ""
        for ch in rhs:
            depth += {"(": 1, ")": -1}.get(ch, 0)
            if ch == "," and depth == 0:
                targets.append(cur.strip())
                cur = ""
            else:
                cur += ch
        targets.append(cur.strip())
        if len(names) != len(targets):
            raise ValueError(f"not a map: {text!r}")
        images = []
        for n, t in zip(names, targets):
            if t.startswith("pi - "):
                images.append(MapImage(n, t[5:], -1, True))
            elif t.endswith(" + pi"):
                images.append(MapImage(n, t[:-5], 1, True))
            elif t.startswith("-") and re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", t[1:]):
                images.append(MapImage(n, t[1:], -1, False))
            else:
                images.append(MapImage(n, t, 1, False))
        return cls(text, images)

    def apply(self, values: Mapping[str, float]) -> Dict[str, float]:
        """The image of a point (a value per variable; unmoved ones are kept)."""
        out = dict(values)
        for im in self.images:
            out[im.var] = im.sign * _evaluate(im.image, values) + (math.pi if im.plus_pi else 0.0)
        return out

    def __str__(self) -> str:
        return self.text


@dataclass(frozen=True, repr=False, eq=False)
class Global(Result):
    """``obsan global``: per variable global / local with k values / not identifiable,
    the joint count of solutions and the discrete symmetries as maps."""

    system: str
    variables: List[Identifiability]
    solutions: Optional[int]
    maps: List[DiscreteMap]
    solutions_at_most: bool = False
    """``solutions`` is an upper bound (an angle output read modulo pi)."""
    maps_modulo_pi: List[DiscreteMap] = field(default_factory=list)
    """Symmetries of the angle outputs' tangents only: each turns an angle output
    by pi or is not decided on the angles; not symmetries of the model."""
    maps_of_parameters: List[DiscreteMap] = field(default_factory=list)
    """Symmetries of the parameters alone (the input-output route): each keeps
    every input-output relation's coefficients, checked exactly over Q; the initial
    states' images are not sought."""
    route: str = "taylor"
    """``"taylor"`` (parameters and initial states), ``"input-output"`` (the
    outputs' input-output relations: parameters, and the initial states when
    ``states_counted_after_io``) or ``"lie"`` (the iterated Lie derivatives:
    indistinguishable for every input)."""
    fallback: Optional[str] = None
    """Why the Taylor route did not answer, when ``route`` fell back; else None."""
    multi_experiment: bool = False
    """The counts are of multi-experiment identifiability only (asked for, and some
    input-output relation has a zero Wronskian: one experiment may leave more values)."""
    states_counted_after_io: bool = False
    """``route`` is ``"input-output"`` (under the default route) and the initial
    states were counted after it, by the Taylor route with ``fixed_params`` known:
    ``variables`` then lists them too."""
    fixed_params: List[str] = field(default_factory=list)
    """The parameters the input-output relations found globally identifiable, fixed at
    the random point's values for the initial states' count."""

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "Global":
        return cls(
            raw=raw,
            system=raw.get("system", ""),
            variables=[
                Identifiability(
                    v.get("name", ""),
                    v.get("kind", ""),
                    v.get("verdict", ""),
                    v.get("values"),
                    bool(v.get("angle", False)),
                    bool(v.get("at_most", False)),
                )
                for v in raw.get("variables") or []
            ],
            solutions=raw.get("solutions"),
            maps=[DiscreteMap.parse(str(m)) for m in raw.get("maps") or []],
            solutions_at_most=bool(raw.get("solutions_at_most", False)),
            maps_modulo_pi=[DiscreteMap.parse(str(m)) for m in raw.get("maps_modulo_pi") or []],
            maps_of_parameters=[
                DiscreteMap.parse(str(m)) for m in raw.get("maps_of_parameters") or []
            ],
            route=str(raw.get("route") or "taylor"),
            fallback=raw.get("fallback"),
            multi_experiment=bool(raw.get("multi_experiment", False)),
            states_counted_after_io=bool((raw.get("states_after_io") or {}).get("counted", False)),
            fixed_params=[str(p) for p in (raw.get("states_after_io") or {}).get("fixed_params") or []],
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


class AlongStretch(NamedTuple):
    """A degenerate stretch of ``obsan rank --along``: its trajectory and time span,
    its rank, the input relations that name it (``"omega = 0"``), the lost directions
    (reduced echelon basis over ``RankAlong.state``) and whether they are exactly the
    symmetries of the model restricted to those inputs."""

    trajectory: str
    t0: float
    t1: float
    rank: int
    input_relations: List[str]
    lost: List[List[float]]
    matches_symmetries: bool


@dataclass(frozen=True, repr=False, eq=False)
class RankAlong(Result):
    """``obsan rank --along``: window by window, the numerical rank of the sampled
    outputs' sensitivity at the data's states with the recorded inputs; the degenerate
    stretches named; and the rank of the whole dataset (``dataset_rank`` of
    ``dataset_n``: params shared, each trajectory its own start). Every window is in
    ``result["windows"]`` (docs/experiments.md)."""

    system: str
    n: int
    state: List[str]
    ranks: List[int]
    stretches: List[AlongStretch]
    dataset_rank: int
    dataset_n: int

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "RankAlong":
        stretches = [
            AlongStretch(
                trajectory=str(s.get("trajectory", "")),
                t0=float(s.get("t0", 0.0)),
                t1=float(s.get("t1", 0.0)),
                rank=int(s.get("rank", 0)),
                input_relations=[str(x) for x in s.get("input_relations") or []],
                lost=[[float(y) for y in x] for x in s.get("lost") or []],
                matches_symmetries=bool((s.get("symmetry") or {}).get("matches", False)),
            )
            for s in raw.get("stretches") or []
        ]
        data = raw.get("dataset") or {}
        return cls(
            raw=raw,
            system=str(raw.get("system", "")),
            n=int(raw.get("n", 0)),
            state=[str(x) for x in raw.get("state") or []],
            ranks=[int(w.get("rank", 0)) for w in raw.get("windows") or []],
            stretches=stretches,
            dataset_rank=int(data.get("rank", 0)),
            dataset_n=int(data.get("n", 0)),
        )


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


@dataclass(frozen=True, repr=False, eq=False)
class Simulation(Result):
    """``obsan simulate MODEL.sys``: the states and outputs at evenly spaced times.
    ``columns`` starts with ``time``; ``rows`` holds one list of values per time (an
    array when numpy is installed); ``error_estimate`` is within ``tolerance`` (relative
    to ``|value| + 1``)."""

    model: str
    columns: List[str]
    rows: Any
    steps: int
    error_estimate: float
    tolerance: float

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "Simulation":
        return cls(
            raw=raw,
            model=str(raw.get("model", "")),
            columns=[str(c) for c in raw.get("columns") or []],
            rows=arrays(raw.get("rows") or []),
            steps=int(raw.get("steps", 0)),
            error_estimate=float(raw.get("error_estimate", 0.0)),
            tolerance=float(raw.get("tolerance", 0.0)),
        )

    def column(self, name: str) -> List[float]:
        """The values of one column (``time``, a state or an output), in time order."""
        i = self.columns.index(name)
        return [float(r[i]) for r in self.raw.get("rows") or []]


class ImportedModel(NamedTuple):
    """One model an import converted: ``path`` where its ``.sys`` was written, or its
    ``text`` when no ``out`` was given; ``key`` is SI.jl's model key (else ``None``)."""

    system: str
    path: Optional[str]
    text: Optional[str]
    key: Optional[str]


@dataclass(frozen=True, repr=False, eq=False)
class Imported(Result):
    """``obsan import FORMAT SOURCE``: the models converted and the files written.
    ``known_inputs`` are the inputs the conversion made (an SBML ``<piecewise>`` of time is
    ``u_ID``), ``inputs_out`` their written course (for ``simulate_model(inputs_csv=...)``),
    ``values_file`` the file of the source's numbers (JSON ``values``; ``values`` is the
    mapping's method), ``refused`` the messages of the models
    ``si-jl --all`` refused. Each model is ``obsan.load(m.path)``, or ``obsan.loads(m.text)``
    when it was not written."""

    format: str
    source: str
    models: List[ImportedModel]
    values_file: Optional[str]
    known_inputs: List[str]
    inputs_out: Optional[str]
    refused: List[str]

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "Imported":
        def opt(v: Any) -> Optional[str]:
            return None if v is None else str(v)

        return cls(
            raw=raw,
            format=str(raw.get("format", "")),
            source=str(raw.get("source", "")),
            models=[
                ImportedModel(str(m.get("system", "")), opt(m.get("path")), opt(m.get("text")), opt(m.get("key")))
                for m in raw.get("models") or []
            ],
            values_file=opt(raw.get("values")),
            known_inputs=[str(n) for n in raw.get("known_inputs") or []],
            inputs_out=opt(raw.get("inputs_out")),
            refused=[str(r) for r in raw.get("refused") or []],
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


class Curvature(NamedTuple):
    """The curvature test of the outputs a named effect rewrites: the whitened
    residual, pooled over those ``outputs``, regressed on the Legendre
    polynomials 1, x, (3x^2 - 1)/2 of the predicted value scaled to x in [-1, 1]
    over ``span``; ``coefficient`` (in the outputs' units, left at both ends of
    the span) with its studentised ``sd`` and ``z`` (a stand-in above 3.5)."""

    outputs: List[str]
    n: int
    span: Tuple[float, float]
    coefficient: float
    sd: float
    z: float
    correlation_factor: float


def _curvature(c: Optional[Mapping[str, Any]]) -> Optional[Curvature]:
    if c is None:
        return None

    def num(x: Any) -> float:
        return math.nan if x is None else float(x)

    span = c.get("span") or [None, None]
    return Curvature(
        [str(o) for o in c.get("outputs") or []],
        int(c.get("n", 0)),
        (num(span[0]), num(span[1])),
        num(c.get("coefficient")),
        num(c.get("sd")),
        num(c.get("z")),
        num(c.get("correlation_factor")),
    )


class NamedEffect(NamedTuple):
    """An effect ``diagnose`` named: its params as :class:`Estimate` s and its
    likelihood-ratio statistic; ``stand_in``: the outputs it rewrites still curve
    in their predicted value in the final fit (:class:`Curvature`), so it stands in
    for an effect of another form (always ``False`` for a suggested one);
    ``weak_under_final_levels``: named under earlier noise levels, its LR at the
    final ones (``lr_final``) is below its critical value (the naming stands)."""

    effect: str
    origin: str
    estimates: Dict[str, Estimate]
    lr: float
    stand_in: bool = False
    curvature: Optional[Curvature] = None
    weak_under_final_levels: bool = False
    lr_final: Optional[float] = None


class Combination(NamedTuple):
    """Two params ``diagnose`` finds fixed only in combination (``|r| >= 0.9``):
    ``params[0] + weight * params[1]`` along the smallest-variance direction of
    their joint covariance (each param scaled by its sd), in the units of
    ``params[0]``, as an :class:`Estimate` (model sd) with its cluster-robust sd.
    ``values`` and ``robust_covariance`` are the two params' own (cross term
    included); ``named``: both effects are named (else two suggested ones fitted
    together); ``established``: its Wald z clears the critical value."""

    params: Tuple[str, str]
    effects: Tuple[str, str]
    weight: float
    estimate: Estimate
    robust_sd: float
    r: float
    values: Tuple[float, float]
    robust_covariance: Tuple[Tuple[float, float], Tuple[float, float]]
    named: bool
    established: bool

    def at(self, weight: float) -> Estimate:
        """``params[0] + weight * params[1]`` with its cluster-robust sd: to compare
        along another diagnosis's direction."""
        (a, b), (c, d) = self.robust_covariance
        var = a + weight * (b + c) + weight * weight * d
        sd = math.sqrt(var) if var >= 0 else math.nan
        return Estimate(self.values[0] + weight * self.values[1], sd)


def _combination(c: Mapping[str, Any]) -> Combination:
    def num(x: Any) -> float:
        return math.nan if x is None else float(x)

    def pair(x: Any) -> Tuple[float, float]:
        return (num(x[0]), num(x[1]))

    rc = c.get("robust_covariance") or [[None, None], [None, None]]
    return Combination(
        (str(c["params"][0]), str(c["params"][1])),
        (str(c["effects"][0]), str(c["effects"][1])),
        num(c.get("weight")),
        Estimate(num(c.get("estimate")), num(c.get("sd"))),
        num(c.get("robust_sd")),
        num(c.get("r")),
        pair(c.get("values") or [None, None]),
        (pair(rc[0]), pair(rc[1])),
        bool(c.get("named")),
        bool(c.get("established")),
    )


class Competing(NamedTuple):
    """A generated winner and a file candidate ``diagnose`` fitted together:
    each one's LR alone, the joint fit's estimates, each one's Wald z beside the
    other against its critical value, the residual structure each one's own fit
    leaves (``[test, z]``), and the one still ``established`` (named), or
    ``None``: competing explanations, not separated by these data; then
    ``named_form``, when each was significant alone (one effect in two
    forms), is the one named, the stronger together."""

    round: int
    effects: Tuple[str, str]
    lr_alone: Tuple[float, float]
    estimates: Dict[str, Estimate]
    wald_z: Tuple[float, float]
    wald_z_critical: Tuple[float, float]
    structure: Tuple[List[Tuple[str, float]], List[Tuple[str, float]]]
    established: Optional[str]
    named_form: Optional[str] = None


def _competing(c: Mapping[str, Any]) -> Competing:
    def num(x: Any) -> float:
        return math.nan if x is None else float(x)

    def pair(x: Any) -> Tuple[float, float]:
        x = x or [None, None]
        return (num(x[0]), num(x[1]))

    def tests(x: Any) -> List[Tuple[str, float]]:
        return [(str(t[0]), num(t[1])) for t in x or []]

    st = c.get("structure") or [[], []]
    est = c.get("established")
    return Competing(
        int(c.get("round", 0)),
        (str(c["effects"][0]), str(c["effects"][1])),
        pair(c.get("lr_alone")),
        {str(e[0]): Estimate(num(e[1]), num(e[2])) for e in c.get("estimates") or []},
        pair(c.get("wald_z")),
        pair(c.get("wald_z_critical")),
        (tests(st[0]), tests(st[1])),
        None if est is None else str(est),
        None if c.get("named_form") is None else str(c["named_form"]),
    )


@dataclass(frozen=True, repr=False, eq=False)
class Diagnosis(Result):
    """``obsan diagnose``: the named effects (in order), those only suggested (LR
    significant, Wald z not), the pairs fixed only in combination
    (:class:`Combination`), the candidates fitted together as competing
    explanations (:class:`Competing`), whether the nominal fit converged, the final fit; and
    ``extended_sys``, the model with the named effects added."""

    model: str
    named: List[NamedEffect]
    suggested: List[NamedEffect]
    combinations: List[Combination]
    competing: List[Competing]
    nominal_converged: bool
    params: Dict[str, Estimate]
    extended_sys: Optional[str]

    @classmethod
    def of(cls, raw: Dict[str, Any]) -> "Diagnosis":
        def effects(key: str) -> List[NamedEffect]:
            return [
                NamedEffect(
                    n.get("effect", ""),
                    n.get("origin", ""),
                    {e[0]: Estimate(e[1], e[2]) for e in n.get("estimates") or []},
                    float(n.get("lr") or 0.0),
                    bool(n.get("stand_in", False)),
                    _curvature(n.get("curvature")),
                    bool(n.get("weak_under_final_levels", False)),
                    None if n.get("lr_final") is None else float(n["lr_final"]),
                )
                for n in raw.get(key) or []
            ]

        final = raw.get("final_fit") or {}
        params = {p[0]: Estimate(p[1], p[2]) for p in final.get("params") or []}
        return cls(
            raw=raw,
            model=str(raw.get("model", "")),
            named=effects("named"),
            suggested=effects("suggested"),
            combinations=[_combination(c) for c in raw.get("combinations") or []],
            competing=[_competing(c) for c in raw.get("competing") or []],
            nominal_converged=bool(raw.get("nominal_converged", True)),
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
