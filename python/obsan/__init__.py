"""obsan from Python: exact nonlinear observability analysis and sensor self-calibration.

Every function runs the ``obsan`` command line's own code in-process and returns a typed
result (:class:`Rank`, :class:`Symmetries`, :class:`Calibration`, ...): a frozen dataclass
whose fields are what programs usually need, and which is also a read-only mapping of
exactly what ``obsan ... --json`` prints (``result["key"]``, ``result.to_dict()``).
Numeric lists become numpy arrays when numpy is installed (``obsan.NUMPY = False`` keeps
lists). In Jupyter, results show as tables and formulas as LaTeX. See docs/python.md.

Errors: a wrong argument type is a ``TypeError`` and a missing input file a
``FileNotFoundError``, both before anything runs; what the CLI refuses (exit code 2: bad
input, a limit, a timeout) raises :class:`ObsanError`, a ``ValueError`` carrying the CLI's
``file:line:col: ...`` text. A check that ran and failed (exit code 1: ``check``,
``verify``, ``modes``) is a value, not an exception.
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, Iterable, List, Mapping, NamedTuple, Optional, Sequence, Tuple, Union

from . import _native
from . import _args as A
from ._args import Flags, Number, PathLike, existing, integer
from ._native import ObsanError, __version__
from ._results import (
    Calibration,
    Check,
    Combination,
    Competing,
    CramerRao,
    Curvature,
    Design,
    Diagnosis,
    DiscreteMap,
    Estimate,
    Expression,
    Global,
    Identifiability,
    Imported,
    ImportedModel,
    LieDerivative,
    LieDerivatives,
    MapImage,
    Modes,
    MonteCarloTable,
    NamedEffect,
    AlongStretch,
    Rank,
    RankAlong,
    ReducedUnknownInput,
    Result,
    Simulation,
    Symmetries,
    SystemInfo,
    Verification,
    arrays,
)

__all__ = [
    "ObsanError",
    "System",
    "load",
    "loads",
    "system",
    "simplify",
    "diff",
    "calibrate",
    "crlb",
    "diagnose",
    "simulate",
    "simulate_model",
    "import_sbml",
    "import_petab",
    "import_si_jl",
    "import_strike_goldd",
    "Imported",
    "ImportedModel",
    "montecarlo",
    "montecarlo_merge",
    "verify",
    "schema",
    "run",
    "Run",
    "Result",
    "SystemInfo",
    "Rank",
    "RankAlong",
    "AlongStretch",
    "Symmetries",
    "Modes",
    "ReducedUnknownInput",
    "Global",
    "Identifiability",
    "DiscreteMap",
    "MapImage",
    "LieDerivatives",
    "LieDerivative",
    "Check",
    "Design",
    "Expression",
    "Verification",
    "Calibration",
    "CramerRao",
    "Combination",
    "Competing",
    "Diagnosis",
    "NamedEffect",
    "Curvature",
    "MonteCarloTable",
    "Estimate",
    "Simulation",
    "NUMPY",
    "PROGRESS",
    "__version__",
]

#: Convert numeric lists to numpy arrays (when numpy is importable).
NUMPY = True

#: Show the progress of long commands (diagnose, montecarlo) on stderr. Off by default
#: in Python, where stderr is a notebook cell or a log, not a terminal.
PROGRESS = False

#: The name ``loads`` gives its text in messages: ``<string>:3:7: ...``.
STRING_NAME = "<string>"

Settings = Optional[Mapping[str, Number]]
Names = Union[str, Iterable[str], None]


class Run(NamedTuple):
    """A command's exit code (0, or 1 when a check it performs failed) and its
    ``--json`` value as plain Python data (``None`` for a command that prints nothing)."""

    code: int
    value: Any


def run(*argv: Union[str, PathLike, Number], source: Optional[Tuple[str, str]] = None) -> Run:
    """Run ``obsan ARGV...`` in-process and return its exit code and parsed stdout.

    The escape hatch for any flag the typed functions do not name. ARGV must ask for
    ``--json`` where the command has it. ``source`` is an optional ``(name, text)`` file
    held in memory. Raises :class:`ObsanError` on exit code 2.
    """
    from ._args import arg

    argv_text = [arg(a) for a in argv]
    if hasattr(_native, "set_progress"):
        _native.set_progress(bool(PROGRESS))
    code, out = _native.run_json(argv_text, source)
    return Run(code, json.loads(out))


def schema(command: str) -> Dict[str, Any]:
    """``obsan schema COMMAND``: the JSON Schema of a command's ``--json`` output, which is
    also the mapping its result object wraps (e.g. ``schema("calibrate")["properties"]``
    are the keys of :func:`calibrate`'s result). Names: ``obsan schema --list``; docs/json.md."""
    v = run("schema", A.text("schema: command", command)).value
    if not isinstance(v, dict):
        raise ObsanError(f"obsan schema {command} printed no JSON object")
    return v


def _value(f: Flags, source: Optional[Tuple[str, str]] = None) -> Dict[str, Any]:
    v = run(*f.argv, "--json", source=source).value
    if not isinstance(v, dict):
        raise ObsanError(f"obsan {f.argv[0]} printed no JSON object")
    return v


def _experiments(f: Flags, experiments: Union[str, Iterable[str], None]) -> Flags:
    """``"auto"``, a file of experiments, or specs like ``"q: q=0.9"`` (one or a list)."""
    if experiments is None:
        return f
    if isinstance(experiments, (str, os.PathLike)):
        e = A.path("experiments", experiments)
        if e == "auto" or os.path.exists(e):
            return f.text("--experiments", e)
        return f.texts("--experiment", [e])
    return f.texts("--experiment", experiments)


def _limits(f: Flags, timeout: Optional[float], max_terms: Optional[int]) -> Flags:
    return f.number("--timeout", timeout).integer("--max-terms", max_terms)


class System:
    """A ``.sys`` system, read from a file (:func:`load`), text (:func:`loads`) or Python
    values (:func:`system`). Each method runs the CLI command of the same name on it.

    Common keywords: ``input`` a restriction declared in the file (``input="q"`` is the
    paper's circles, eq. 17); ``set`` values of known constants (``{"q": 0.9}``, read
    exactly: a float by its shortest repr, a ``Fraction`` as p/q); ``seed`` of the random
    evaluation points; ``timeout`` in seconds; ``max_terms`` the engine's size budget.
    """

    def __init__(self, path: str, text: Optional[str] = None) -> None:
        self.path = path
        self.text = text
        self._source = (path, text) if text is not None else None
        # Read and checked now, so a bad file is an error here.
        self.info: SystemInfo = self.show()

    @property
    def name(self) -> str:
        return self.info.system

    def __repr__(self) -> str:
        where = "text" if self.text is not None else repr(self.path)
        return f"<obsan.System {self.name} from {where}>"

    def _repr_latex_(self) -> str:
        return self.info._repr_latex_()

    def _flags(self, command: str, input: Optional[str], set: Settings) -> Flags:
        return Flags(command, self.path).text("--input", input).pairs("--set", set)

    def _get(self, f: Flags) -> Dict[str, Any]:
        return _value(f, self._source)

    def show(self, *, input: Optional[str] = None, set: Settings = None) -> SystemInfo:
        """``obsan show``: the input-affine normal form."""
        return SystemInfo.of(self._get(self._flags("show", input, set)))

    def rank(
        self,
        *,
        input: Optional[str] = None,
        set: Settings = None,
        seed: Optional[int] = None,
        order: Optional[int] = None,
        timeout: Optional[float] = None,
        max_terms: Optional[int] = None,
    ) -> Rank:
        """``obsan rank``: the observability rank condition (exact at full rank, else a
        lower bound with ``error_bound``). With unknown inputs in the model, ``order`` is
        the highest output derivative examined."""
        f = self._flags("rank", input, set).integer("--seed", seed).integer("--order", order)
        return Rank.of(self._get(_limits(f, timeout, max_terms)))

    def experiments(
        self,
        experiments: Union[str, Iterable[str]] = "auto",
        *,
        input: Optional[str] = None,
        set: Settings = None,
        seed: Optional[int] = None,
        timeout: Optional[float] = None,
        max_terms: Optional[int] = None,
    ) -> Rank:
        """``obsan rank`` over several experiments (docs/experiments.md).

        ``"auto"`` (default): the smallest number of generic experiments (under the
        restriction ``input``, or with free inputs) after which the rank stops growing,
        and which special constant values are degenerate. A list of specs, e.g.
        ``["q: q=0.9", "q: q=0", "q: q=-1"]``: the rank of those experiments stacked
        (params shared, states ``x@k`` per experiment). A path: the experiments file."""
        f = self._flags("rank", input, set).integer("--seed", seed)
        return Rank.of(self._get(_limits(_experiments(f, experiments), timeout, max_terms)))

    def rank_known(
        self,
        known: Settings = None,
        generic: Names = None,
        *,
        input: Optional[str] = None,
        set: Settings = None,
        seed: Optional[int] = None,
        known_order: Optional[int] = None,
        timeout: Optional[float] = None,
        max_terms: Optional[int] = None,
    ) -> Rank:
        """``obsan rank --known``: the rank test with known initial conditions, e.g.
        ``known={"S": 0}`` (exact values, evaluated at that point: a certified lower
        bound, with the generic rank as upper bound) and ``generic=["x2"]`` (known but
        generic). See docs/experiments.md for what is certified."""
        f = self._flags("rank", input, set).pairs("--known", known).texts("--known-generic", generic)
        f = f.integer("--seed", seed).integer("--known-order", known_order)
        return Rank.of(self._get(_limits(f, timeout, max_terms)))

    def rank_along(
        self,
        dataset: PathLike,
        *,
        window: Optional[Number] = None,
        truth: Optional[PathLike] = None,
        set: Settings = None,
        timeout: Optional[float] = None,
    ) -> RankAlong:
        """``obsan rank --along``: observability along a dataset, window by window
        (``window`` seconds, default 10), at the states of ``truth`` (default: the
        dataset's truth.json: simulated truth or MRCLAM's Vicon truth; a fit's values in
        that shape). The degenerate stretches are named by their input relations, lost
        directions and the symmetries they match (docs/experiments.md)."""
        f = self._flags("rank", None, set)
        f.argv += ["--along", existing("rank_along: dataset", dataset)]
        f = f.number("--window", window)
        if truth is not None:
            f.argv += ["--truth", existing("rank_along: truth", truth)]
        return RankAlong.of(self._get(_limits(f, timeout, None)))

    def design(
        self,
        candidates: Optional[PathLike] = None,
        *,
        target: Names = None,
        families: bool = False,
        input: Optional[str] = None,
        set: Settings = None,
        max_subsets: Optional[int] = None,
        seed: Optional[int] = None,
        timeout: Optional[float] = None,
        max_terms: Optional[int] = None,
    ) -> Design:
        """``obsan design``: which sensor, which trajectory (docs/experiments.md).

        ``candidates``: a candidates file (``candidate NAME [cost C]`` lines, each followed
        by ``output`` statements): the minimal sets (by count, then cost) that make every
        variable, or those of ``target``, observable, each with the symmetries it breaks
        (``result.sets``, ``result["sensors"]``). Without ``candidates`` (or with
        ``families=True``): which input families (the model's restrictions) identify
        everything alone, in several experiments or combined (``result["inputs"]``)."""
        f = self._flags("design", input, set)
        if candidates is not None:
            f.argv += ["--candidates", existing("design: candidates", candidates)]
        if target is not None:
            names = [target] if isinstance(target, str) else list(target)
            f = f.text("--target", ",".join(A.text("target", t) for t in names))
        f = f.switch("--families", families).integer("--max-subsets", max_subsets)
        f = f.integer("--seed", seed)
        return Design.of(self._get(_limits(f, timeout, max_terms)))

    def symmetries(
        self,
        *,
        input: Optional[str] = None,
        set: Settings = None,
        experiments: Union[str, Iterable[str], None] = None,
        seed: Optional[int] = None,
        exact: bool = False,
        timeout: Optional[float] = None,
        max_terms: Optional[int] = None,
    ) -> Symmetries:
        """``obsan symmetries``: a certified basis of the continuous symmetries
        (``exact=True`` takes the exact route however long it takes)."""
        f = _experiments(self._flags("symmetries", input, set), experiments)
        f = f.integer("--seed", seed).switch("--exact", exact)
        return Symmetries.of(self._get(_limits(f, timeout, max_terms)))

    def modes(
        self,
        *,
        input: Optional[str] = None,
        set: Settings = None,
        experiments: Union[str, Iterable[str], None] = None,
        seed: Optional[int] = None,
        out: Optional[PathLike] = None,
        force: bool = False,
        timeout: Optional[float] = None,
        max_terms: Optional[int] = None,
    ) -> Modes:
        """``obsan modes``: observable modes and the reduced system, proven exactly.
        ``out="prefix"`` also writes prefix.sys and prefix.dec (``force=True`` replaces
        them)."""
        f = _experiments(self._flags("modes", input, set), experiments)
        f = f.integer("--seed", seed).path("--out", out).switch("--force", force)
        return Modes.of(self._get(_limits(f, timeout, max_terms)))

    def global_identifiability(
        self,
        *,
        input: Optional[str] = None,
        set: Settings = None,
        seed: Optional[int] = None,
        timeout: Optional[float] = None,
        max_terms: Optional[int] = None,
        route: Optional[str] = None,
        multi_experiment: bool = False,
    ) -> Global:
        """``obsan global``: per param and initial state, global / local with k values /
        not identifiable; the joint count and the exact discrete symmetries. ``route``:
        ``"auto"`` (default: the Taylor system, else the input-output relations, else
        the Lie derivatives), ``"taylor"``, ``"io"`` or ``"lie"`` (indistinguishable for
        every input); ``Global.route`` says which answered. ``multi_experiment=True``
        counts the params over enough independent experiments (the input-output
        relations, also with a zero Wronskian); ``Global.multi_experiment`` says whether
        the counts are of that kind only."""
        f = self._flags("global", input, set).integer("--seed", seed).text("--route", route)
        f = f.switch("--multi-experiment", multi_experiment)
        return Global.of(self._get(_limits(f, timeout, max_terms)))

    def lie(
        self,
        order: int,
        *,
        input: Optional[str] = None,
        set: Settings = None,
        timeout: Optional[float] = None,
        max_terms: Optional[int] = None,
    ) -> LieDerivatives:
        """``obsan lie``: the Lie derivatives of the outputs up to ``order``."""
        f = self._flags("lie", input, set).text("--order", integer("order", order))
        return LieDerivatives.of(self._get(_limits(f, timeout, max_terms)))

    def check(
        self,
        modes: Union[str, Iterable[str]],
        *,
        input: Optional[str] = None,
        set: Settings = None,
        seed: Optional[int] = None,
        exact: bool = False,
        timeout: Optional[float] = None,
        max_terms: Optional[int] = None,
    ) -> Check:
        """``obsan check``: candidate observable modes against eq. (11). A failed mode
        is a value (``result.modes[m]`` false), not an exception."""
        f = self._flags("check", input, set).texts("--mode", modes)
        f = f.integer("--seed", seed).switch("--exact", exact)
        return Check.of(self._get(_limits(f, timeout, max_terms)))


def load(path: PathLike) -> System:
    """Read a ``.sys`` file. Errors name the path, line and column."""
    return System(existing("load: path", path))


def loads(text: str) -> System:
    """A system from ``.sys`` text; errors read ``<string>:LINE:COL: ...``."""
    return System(STRING_NAME, A.text("loads: text", text))


def system(
    name: str,
    *,
    states: Sequence[str],
    dynamics: Mapping[str, str],
    outputs: Mapping[str, str],
    params: Sequence[str] = (),
    consts: Sequence[str] = (),
    inputs: Sequence[str] = (),
    restrictions: Optional[Mapping[str, str]] = None,
    description: Optional[str] = None,
) -> System:
    """A system from Python values, without a file::

        s = obsan.system(
            "decay",
            states=["x"], params=["a"],
            dynamics={"x": "-a*x"},
            outputs={"y": "x"},
        )

    ``dynamics`` maps each state to its right-hand side (input-affine in ``inputs``);
    ``restrictions`` maps a restriction's name to its text after the colon (``{"q":
    "wR = nu, wL = q*nu"}``). Errors point into the generated ``.sys`` text, which is
    ``System.text``."""
    lines = [f"system {A.text('system: name', name)}"]
    if description is not None:
        lines += [f"description {d}" for d in A.text("description", description).splitlines()]

    def names(kind: str, xs: Sequence[str]) -> None:
        xs = [xs] if isinstance(xs, str) else list(xs)
        if xs:
            lines.append(f"{kind} " + ", ".join(A.text(f"system: {kind}", x) for x in xs))

    names("state", states)
    names("param", params)
    names("const", consts)
    names("input", inputs)
    for s, rhs in dynamics.items():
        lines.append(f"{A.text('system: state', s)}' = {A.text('system: dynamics', rhs)}")
    for y, h in outputs.items():
        lines.append(f"output {A.text('system: output', y)} = {A.text('system: outputs', h)}")
    for r, body in (restrictions or {}).items():
        lines.append(f"restrict {A.text('system: restriction', r)}: {A.text('system: restrictions', body)}")
    return System(STRING_NAME, "\n".join(lines) + "\n")


def simplify(expr: str, *, timeout: Optional[float] = None, max_terms: Optional[int] = None) -> Expression:
    """``obsan simplify``: the exact canonical form of ``expr``."""
    f = Flags("simplify", A.text("simplify: expr", expr))
    return Expression.of(_value(_limits(f, timeout, max_terms)))


def diff(
    expr: str, var: str, *, timeout: Optional[float] = None, max_terms: Optional[int] = None
) -> Expression:
    """``obsan diff``: d expr / d var, in canonical form."""
    f = Flags("diff", A.text("diff: expr", expr), A.text("diff: var", var))
    return Expression.of(_value(_limits(f, timeout, max_terms)))


def verify(
    path: PathLike,
    *,
    seed: Optional[int] = None,
    exact: bool = False,
    timeout: Optional[float] = None,
    max_terms: Optional[int] = None,
) -> Verification:
    """``obsan verify``: a decomposition file's exact checks (a failed check is a value)."""
    f = Flags("verify", existing("verify: path", path)).integer("--seed", seed).switch("--exact", exact)
    return Verification.of(_value(_limits(f, timeout, max_terms)))


def _sim(
    f: Flags,
    q: Union[Number, Sequence[Number], None],
    sigma_beta_deg: Optional[float],
    k: Optional[float],
    iota: Optional[float],
    dq: Optional[float],
    nu: Optional[float],
    speed_profile: Optional[str],
    bearing_rate: Optional[float],
    bearings: Optional[int],
    d0: Optional[float],
    effect: Optional[Mapping[str, Number]],
    inputs: Optional[PathLike],
    seed: Optional[int],
) -> Flags:
    f = f.numbers("--set", q, key="q").number("--sigma-beta-deg", sigma_beta_deg)
    f = f.number("--k", k)
    f = f.number("--iota", iota).number("--dq", dq).number("--nu", nu)
    f = f.text("--speed-profile", speed_profile).number("--bearing-rate", bearing_rate)
    f = f.integer("--bearings", bearings).number("--d0", d0).pairs("--effect", effect)
    if inputs is not None:
        f = f.text("--inputs", existing("inputs", inputs))
    return f.integer("--seed", seed)


def simulate(
    out: PathLike,
    *,
    force: bool = False,
    q: Union[Number, Sequence[Number], None] = None,
    sigma_beta_deg: Optional[float] = None,
    k: Optional[float] = None,
    iota: Optional[float] = None,
    dq: Optional[float] = None,
    nu: Optional[float] = None,
    speed_profile: Optional[str] = None,
    bearing_rate: Optional[float] = None,
    bearings: Optional[int] = None,
    d0: Optional[float] = None,
    effect: Optional[Mapping[str, Number]] = None,
    inputs: Optional[PathLike] = None,
    seed: Optional[int] = None,
    timeout: Optional[float] = None,
) -> str:
    """``obsan simulate``: write the paper's simulated dataset (section VI-A) to the
    new folder ``out`` and return its path; the truth is in ``out/truth.json``.

    ``q`` wheel-speed ratios, one circle each (default 0.9, 0, -1); ``sigma_beta_deg``
    bearing noise (deg, default 1); ``k`` encoder noise K; ``iota`` non-circular paths;
    ``dq`` executed-ratio error; ``nu`` right wheel speed (rad/s); ``speed_profile``
    ``constant``, ``sine:A:T`` or ``stopgo:RUN:PAUSE``; ``bearing_rate`` per second or
    ``bearings`` per trajectory; ``d0`` initial distance (m); ``effect`` hidden effects
    (``{"bearing_scale": 0.04}``); ``inputs`` a CSV wheel-speed history; ``force=True``
    replaces a folder obsan wrote."""
    o = A.path("simulate: out", out)
    f = Flags("simulate", "--out", o).switch("--force", force)
    f = _sim(f, q, sigma_beta_deg, k, iota, dq, nu, speed_profile, bearing_rate, bearings, d0, effect, inputs, seed)
    run(*f.number("--timeout", timeout).argv)
    return o


def simulate_model(
    model: PathLike,
    *,
    until: Number,
    every: Number,
    values: Optional[PathLike] = None,
    set: Settings = None,
    init: Settings = None,
    inputs: Optional[Mapping[str, Union[Number, str]]] = None,
    inputs_csv: Optional[PathLike] = None,
    out: Optional[PathLike] = None,
    force: bool = False,
    timeout: Optional[float] = None,
) -> Simulation:
    """``obsan simulate MODEL.sys``: integrate any model from ``values`` (a file of
    ``name = value`` lines, as ``obsan import sbml --values`` writes), ``set`` params,
    ``init`` initial states and ``inputs``, each a number or an expression of time ``t``
    (``{"u": 0.2}``, ``{"u": "sin(t)"}``), or ``inputs_csv``, a time course (header
    ``t,<inputs>``, linear between rows, two rows at one ``t`` a step), at times 0,
    ``every``, ... up to ``until``; ``out`` also writes the CSV. A missing value raises
    :class:`ObsanError` naming it."""
    f = Flags("simulate", existing("simulate_model: model", model))
    if values is not None:
        f = f.text("--values", existing("simulate_model: values", values))
    if inputs_csv is not None:
        f = f.text("--inputs", existing("simulate_model: inputs_csv", inputs_csv))
    f = f.pairs("--set", set).pairs("--init", init).pairs("--input", inputs)
    f = f.number("--until", until).number("--every", every)
    f = f.path("--out", out).switch("--force", force).number("--timeout", timeout)
    return Simulation.of(_value(f))


def _import(f: Flags, out: Optional[PathLike], force: bool, max_terms: Optional[int]) -> Imported:
    f = f.path("--out", out).switch("--force", force).integer("--max-terms", max_terms)
    return Imported.of(_value(f))


def import_sbml(
    source: PathLike,
    out: Optional[PathLike] = None,
    *,
    observe: Names = None,
    values: Optional[PathLike] = None,
    inputs_out: Optional[PathLike] = None,
    until: Optional[Number] = None,
    force: bool = False,
    max_terms: Optional[int] = None,
) -> Imported:
    """``obsan import sbml``: an SBML model to ``.sys``, written to ``out`` (else its text is
    in ``result.models[0].text``). ``observe`` the measured ids (default every state);
    ``values`` a file for the model's numbers; ``inputs_out`` a CSV of the known inputs'
    exact course over ``[0, until]`` (an SBML ``<piecewise>`` of time is a known input),
    which :func:`simulate_model` reads as ``inputs_csv``. A refusal raises
    :class:`ObsanError` naming the element's line and writes nothing."""
    f = Flags("import", "sbml", existing("import_sbml: source", source)).texts("--observe", observe)
    f = f.path("--values", values).path("--inputs-out", inputs_out).number("--until", until)
    return _import(f, out, force, max_terms)


def import_petab(
    problem: PathLike,
    out: Optional[PathLike] = None,
    *,
    condition: Optional[str] = None,
    force: bool = False,
    max_terms: Optional[int] = None,
) -> Imported:
    """``obsan import petab``: a PEtab v1 problem (its YAML file) to ``.sys``; observables
    become outputs, estimated parameters params, fixed ones consts; one model copy per
    condition, or only ``condition``."""
    f = Flags("import", "petab", existing("import_petab: problem", problem)).text("--condition", condition)
    return _import(f, out, force, max_terms)


def import_si_jl(
    source: PathLike,
    out: Optional[PathLike] = None,
    *,
    model: Optional[str] = None,
    all: Optional[PathLike] = None,
    force: bool = False,
    max_terms: Optional[int] = None,
) -> Imported:
    """``obsan import si-jl``: StructuralIdentifiability.jl's ``@ODEmodel`` text to ``.sys``:
    ``model`` picks one of a file's models by key; ``all`` a folder that receives every
    model as ``KEY.sys`` (a model refused raises :class:`ObsanError` after the others are
    written, as the command exits 2)."""
    f = Flags("import", "si-jl", existing("import_si_jl: source", source)).text("--model", model)
    return _import(f.path("--all", all), out, force, max_terms)


def import_strike_goldd(
    source: PathLike,
    out: Optional[PathLike] = None,
    *,
    force: bool = False,
    max_terms: Optional[int] = None,
) -> Imported:
    """``obsan import strike-goldd``: a STRIKE-GOLDD ``z_create_NAME.m`` model file to ``.sys``
    (``x`` states, ``p`` params, ``u`` known inputs, ``w`` unknown inputs, ``f``, ``h``)."""
    f = Flags("import", "strike-goldd", existing("import_strike_goldd: source", source))
    return _import(f, out, force, max_terms)


def calibrate(
    dataset: PathLike,
    method: str = "ml",
    *,
    d0: Optional[float] = None,
    sigma_beta_deg: Optional[float] = None,
    plot: Optional[PathLike] = None,
    force: bool = False,
    timeout: Optional[float] = None,
) -> Calibration:
    """``obsan calibrate``: the paper's estimator (section V) on a dataset of circles;
    phi, psi, eta, delta, xi (and with ``d0`` rho, r_right, r_left, B) with standard
    deviations. ``method`` is ``det``, ``ls``, ``cekf`` or ``ml``; ``plot`` a folder for
    Figures 5–7 and ``curves.json``."""
    m = A.text("calibrate: method", method)
    if m not in ("det", "ls", "cekf", "ml"):
        raise ValueError(f"calibrate: method must be det, ls, cekf or ml, not {m!r}")
    f = Flags("calibrate", existing("calibrate: dataset", dataset), "--method", m)
    f = f.number("--d0", d0).number("--sigma-beta-deg", sigma_beta_deg)
    f = f.path("--plot", plot).switch("--force", force).number("--timeout", timeout)
    return Calibration.of(_value(f))


# The set-up keywords repeat simulate()'s: each function keeps a real signature
# (help(), IDEs, mypy --strict) rather than **kwargs; _sim() is the one place using them.
def crlb(
    dataset: Optional[PathLike] = None,
    *,
    q: Union[Number, Sequence[Number], None] = None,
    sigma_beta_deg: Optional[float] = None,
    k: Optional[float] = None,
    iota: Optional[float] = None,
    dq: Optional[float] = None,
    nu: Optional[float] = None,
    speed_profile: Optional[str] = None,
    bearing_rate: Optional[float] = None,
    bearings: Optional[int] = None,
    d0: Optional[float] = None,
    effect: Optional[Mapping[str, Number]] = None,
    inputs: Optional[PathLike] = None,
    seed: Optional[int] = None,
    timeout: Optional[float] = None,
) -> CramerRao:
    """``obsan crlb``: the Cramér–Rao bound for a dataset (at its ML estimate) or for a
    simulated set-up given by :func:`simulate`'s keywords."""
    f = Flags("crlb")
    if dataset is not None:
        f.argv.append(existing("crlb: dataset", dataset))
    f = _sim(f, q, sigma_beta_deg, k, iota, dq, nu, speed_profile, bearing_rate, bearings, d0, effect, inputs, seed)
    return CramerRao.of(_value(f.number("--timeout", timeout)))


def diagnose(
    model: Union[PathLike, System],
    data: PathLike,
    effects: Optional[PathLike] = None,
    *,
    report: Optional[PathLike] = None,
    force: bool = False,
    init: Optional[Mapping[str, Number]] = None,
    alpha: Optional[float] = None,
    max_effects: Optional[int] = None,
    input_noise: Optional[str] = None,
    generated: bool = True,
    timeout: Optional[float] = None,
) -> Diagnosis:
    """``obsan diagnose``: fit ``model`` (a path or a :class:`System`) to ``data``, test
    the residuals, name the significant effects (from ``effects``, default the model's
    ``.eff``, and generated from the model's structure unless ``generated=False``).
    ``report`` writes a report folder (all or nothing; ``force=True`` replaces one);
    ``input_noise`` is ``auto``, ``stated``, ``estimate`` or ``none``.

    ``named`` holds only established effects; ``suggested`` those whose LR clears its
    critical value but whose Wald z does not; ``nominal_converged`` is false when the
    fit from the start had stopped short (``result["refits"]`` says where from)."""
    source = None
    if isinstance(model, System):
        source, m = model._source, model.path
        if source is None:
            m = existing("diagnose: model", m)
    else:
        m = existing("diagnose: model", model)
    f = Flags("diagnose", "--model", m, "--data", existing("diagnose: data", data))
    if effects is not None:
        f.argv += ["--effects", existing("diagnose: effects", effects)]
    f = f.path("--report", report).switch("--force", force).pairs("--init", init)
    f = f.number("--alpha", alpha).integer("--max-effects", max_effects)
    if input_noise is not None and A.text("input_noise", input_noise) not in ("auto", "stated", "estimate", "none"):
        raise ValueError(f"diagnose: input_noise must be auto, stated, estimate or none, not {input_noise!r}")
    f = f.text("--input-noise", input_noise).switch("--no-generated", not generated)
    return Diagnosis.of(_value(f.number("--timeout", timeout), source))


def montecarlo(
    *,
    table: Union[int, str, None] = None,
    runs: Optional[int] = None,
    cell: Optional[int] = None,
    shard: Union[str, Tuple[int, int], None] = None,
    threads: Optional[int] = None,
    seed: Optional[int] = None,
    timeout: Optional[float] = None,
) -> Any:
    """``obsan montecarlo``: the paper's Tables IV–VII (``table`` 4–7, default all;
    ``runs`` per cell; ``cell`` one row of set-ups) as a list of
    :class:`MonteCarloTable` (docs/montecarlo.md).

    With ``shard="K/N"`` (or ``(K, N)``) it runs that fixed subset of the runs and
    returns the partial result, a plain dict (meant for :func:`montecarlo_merge`;
    ``json.dump`` writes it as ``obsan montecarlo merge`` reads it)."""
    f = Flags("montecarlo")
    if table is not None:
        f.argv += ["--table", table if isinstance(table, str) else integer("table", table)]
    f = f.integer("--runs", runs).integer("--cell", cell)
    if shard is not None:
        if isinstance(shard, tuple):
            shard = f"{integer('shard', shard[0])}/{integer('shard', shard[1])}"
        f = f.text("--shard", shard)
    f = f.integer("--threads", threads).integer("--seed", seed).number("--timeout", timeout)
    value = run(*f.argv, "--json").value
    if shard is not None:
        return value
    return _tables(value)


def _tables(value: Any) -> Any:
    if isinstance(value, list):
        return [MonteCarloTable.of(t) for t in value]
    if isinstance(value, dict) and "table" in value:
        return MonteCarloTable.of(value)
    return arrays(value)


def montecarlo_merge(parts: Iterable[Any]) -> Any:
    """``obsan montecarlo merge``: the partial results of every shard of one sweep (the
    dicts :func:`montecarlo` returns with ``shard=``, or paths of the files the CLI's
    ``--shard K/N --json`` wrote), in any order, as exactly the tables one run gives."""
    import tempfile

    items = list(parts)
    with tempfile.TemporaryDirectory(prefix="obsan-merge-") as d:
        paths: List[str] = []
        for i, p in enumerate(items, 1):
            if isinstance(p, Mapping):
                name = os.path.join(d, f"part{i}.json")
                with open(name, "w", encoding="utf-8") as fh:
                    json.dump(p, fh)
                paths.append(name)
            else:
                paths.append(existing("montecarlo_merge: a part", p))
        return _tables(run("montecarlo", "merge", *paths, "--json").value)


# Kept for code written against 0.1's module layout.
_arrays = arrays
