"""obsan from Python: exact nonlinear observability analysis and sensor self-calibration.

Every function runs the ``obsan`` command line's own code in-process and returns what
``obsan ... --json`` prints, as plain dicts and lists; numeric lists become numpy arrays
when numpy is installed (set ``obsan.NUMPY = False`` to keep lists). See docs/python.md.

Errors (the CLI's exit code 2: bad input, a limit) raise :class:`ObsanError`, a
``ValueError`` carrying the CLI's text (``file:line:col: ...``). A check that ran and
failed (the CLI's exit code 1: ``check``, ``verify``, ``modes``) is a value, not an
exception: the returned dict says what failed, and :func:`run` also gives the code.
"""

from __future__ import annotations

import json
import numbers
import os
from typing import Any, Iterable, Mapping, NamedTuple, Optional, Union

from ._native import ObsanError, __version__
from ._native import run_json as _run_json

__all__ = [
    "ObsanError",
    "System",
    "load",
    "loads",
    "simplify",
    "diff",
    "calibrate",
    "crlb",
    "diagnose",
    "simulate",
    "montecarlo",
    "montecarlo_merge",
    "verify",
    "run",
    "Run",
    "NUMPY",
    "__version__",
]

#: Convert numeric lists to numpy arrays (when numpy is importable).
NUMPY = True

#: The name ``loads`` gives its text in messages: ``<string>:3:7: ...``.
STRING_NAME = "<string>"

PathLike = Union[str, "os.PathLike[str]"]


class Run(NamedTuple):
    """A command's exit code (0, or 1 when a check it performs failed) and its
    ``--json`` value as plain Python data (``None`` for a command that prints nothing)."""

    code: int
    value: Any


def run(*argv: Any, source: Optional[tuple] = None) -> Run:
    """Run ``obsan ARGV...`` in-process and return its exit code and parsed stdout.

    ARGV must ask for ``--json`` where the command has it. ``source`` is an optional
    ``(name, text)`` file held in memory. Raises :class:`ObsanError` on exit code 2.
    """
    code, text = _run_json([_arg(a) for a in argv], source)
    return Run(code, json.loads(text))


def _arg(a: Any) -> str:
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
        return _value(a)
    raise TypeError(f"expected a str, a path or a number, not {type(a).__name__}")


def _text(what: str, a: Any) -> str:
    """A text argument (an expression, a symbol, a method): a str, else TypeError."""
    if not isinstance(a, str):
        raise TypeError(f"{what} must be a str, not {type(a).__name__}")
    return a


def _path(what: str, a: Any) -> str:
    """A path argument: a str or os.PathLike, else TypeError."""
    if not isinstance(a, (str, os.PathLike)):
        raise TypeError(f"{what} must be a path (str or os.PathLike), not {type(a).__name__}")
    return _arg(a)


def _value(x: Any) -> str:
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
    return _arg(x)


def _flags(options: Mapping[str, Any], join: Iterable[str] = ()) -> list:
    """Keyword options as flags: ``max_terms=5`` is ``--max-terms 5``, ``True`` a bare
    flag, ``None``/``False`` nothing; a dict is repeated ``NAME=VALUE`` flags; a list is
    a repeated flag, or one comma-joined value for the names in ``join``."""
    join = set(join)
    out: list = []
    for name, v in options.items():
        flag = "--" + name.replace("_", "-")
        if v is None or v is False:
            continue
        if v is True:
            out.append(flag)
        elif isinstance(v, Mapping):
            for k, x in v.items():
                out += [flag, f"{k}={_value(x)}"]
        elif isinstance(v, (list, tuple)) or _is_array(v):
            items = [_value(x) for x in v]
            if name in join:
                out += [flag, ",".join(items)]
            else:
                for x in items:
                    out += [flag, x]
        else:
            out += [flag, _value(v)]
    return out


def _is_array(v: Any) -> bool:
    return hasattr(v, "tolist") and hasattr(v, "shape")


def _arrays(v: Any) -> Any:
    """Numeric lists (and rectangular lists of them) as numpy arrays."""
    if not NUMPY:
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


def _call(argv: list, source: Optional[tuple] = None) -> Any:
    return _arrays(run(*argv, source=source).value)


_SYSTEM_OPTIONS = ("input", "set", "seed", "timeout", "max_terms")


class System:
    """A ``.sys`` system, read from a file (:func:`load`) or text (:func:`loads`).

    Each method runs the CLI command of the same name on it, with ``--json``;
    keyword options are the command's flags (``input="q"`` is ``--input q``,
    ``set={"q": 0.9}`` is ``--set q=0.9``).
    """

    def __init__(self, path: str, text: Optional[str] = None):
        self.path = path
        self.text = text
        self._source = (path, text) if text is not None else None
        # Read and checked now, so a bad file is an error here.
        self.info = self.show()

    @property
    def name(self) -> str:
        return self.info["system"]

    def __repr__(self) -> str:
        where = "text" if self.text is not None else repr(self.path)
        return f"<obsan.System {self.name} from {where}>"

    def _run(self, command: str, options: Mapping[str, Any], *extra: Any) -> Any:
        return _call(
            [command, self.path, *extra, *_flags(options), "--json"],
            self._source,
        )

    def show(self, input: Optional[str] = None, set: Optional[Mapping] = None, **options: Any) -> dict:
        """``obsan show``: the input-affine normal form."""
        return self._run("show", dict(input=input, set=set, **options))

    def rank(
        self,
        input: Optional[str] = None,
        set: Optional[Mapping] = None,
        seed: Optional[int] = None,
        **options: Any,
    ) -> dict:
        """``obsan rank``: the Hermann–Krener rank test (exact at full rank, else a
        lower bound with ``error_bound``)."""
        return self._run("rank", dict(input=input, set=set, seed=seed, **options))

    def experiments(
        self,
        experiments: Union[str, Iterable[str]] = "auto",
        input: Optional[str] = None,
        set: Optional[Mapping] = None,
        seed: Optional[int] = None,
        **options: Any,
    ) -> dict:
        """``obsan rank`` over several experiments (docs/experiments.md).

        ``"auto"`` (default): the smallest number of generic experiments (under the
        restriction ``input``, or with free inputs) after which the rank stops growing,
        and which special constant values are degenerate. A list of specs, e.g.
        ``["q: q=0.9", "q: q=0", "q: q=-1"]``: the rank of those experiments stacked
        (params shared, states ``x@k`` per experiment). A path: the experiments file."""
        if isinstance(experiments, str):
            if experiments == "auto" or os.path.exists(experiments):
                opts = dict(experiments=experiments, input=input, set=set, seed=seed)
            else:
                opts = dict(experiment=[experiments], set=set, seed=seed)
        else:
            opts = dict(experiment=list(experiments), set=set, seed=seed)
        return self._run("rank", dict(opts, **options))

    def rank_known(
        self,
        known: Optional[Mapping] = None,
        generic: Union[str, Iterable[str], None] = None,
        input: Optional[str] = None,
        set: Optional[Mapping] = None,
        seed: Optional[int] = None,
        **options: Any,
    ) -> dict:
        """``obsan rank --known``: the rank test with known initial conditions, e.g.
        ``known={"S": 0}`` (exact values, evaluated at that point: a certified lower
        bound, with the generic rank as upper bound) and ``generic=["x2"]`` (known but
        generic). See docs/experiments.md for what is certified."""
        generic = [generic] if isinstance(generic, str) else (list(generic) if generic else None)
        return self._run(
            "rank",
            dict(known=known, known_generic=generic, input=input, set=set, seed=seed, **options),
        )

    def design(
        self,
        candidates: Optional[str] = None,
        target: Union[str, Iterable[str], None] = None,
        families: bool = False,
        input: Optional[str] = None,
        set: Optional[Mapping] = None,
        seed: Optional[int] = None,
        **options: Any,
    ) -> dict:
        """``obsan design``: which sensor, which trajectory (docs/experiments.md).

        ``candidates``: a candidates file (``candidate NAME [cost C]`` lines, each followed
        by ``output`` statements): the minimal sets (by count, then cost) that make every
        variable, or those of ``target``, observable, each with the symmetries it breaks
        (``result["sensors"]``). Without ``candidates`` (or with ``families=True``): which
        input families (the model's restrictions) identify everything alone, in several
        experiments or combined (``result["inputs"]``)."""
        target = [target] if isinstance(target, str) else (list(target) if target else None)
        return _call(
            [
                "design",
                self.path,
                *_flags(
                    dict(
                        candidates=candidates,
                        target=target,
                        families=families,
                        input=input,
                        set=set,
                        seed=seed,
                        **options,
                    ),
                    join=("target",),
                ),
                "--json",
            ],
            self._source,
        )

    def symmetries(
        self,
        input: Optional[str] = None,
        set: Optional[Mapping] = None,
        seed: Optional[int] = None,
        exact: bool = False,
        **options: Any,
    ) -> dict:
        """``obsan symmetries``: a certified basis of the continuous symmetries."""
        return self._run("symmetries", dict(input=input, set=set, seed=seed, exact=exact, **options))

    def modes(
        self,
        input: Optional[str] = None,
        set: Optional[Mapping] = None,
        seed: Optional[int] = None,
        **options: Any,
    ) -> dict:
        """``obsan modes``: observable modes and the reduced system, proven exactly.
        ``out="prefix"`` also writes prefix.sys and prefix.dec."""
        return self._run("modes", dict(input=input, set=set, seed=seed, **options))

    def global_identifiability(
        self,
        input: Optional[str] = None,
        set: Optional[Mapping] = None,
        seed: Optional[int] = None,
        **options: Any,
    ) -> dict:
        """``obsan global``: per param and initial state, global / local with k values /
        not identifiable; the joint count and the exact discrete symmetries."""
        return self._run("global", dict(input=input, set=set, seed=seed, **options))

    def lie(self, order: int, input: Optional[str] = None, set: Optional[Mapping] = None, **options: Any) -> dict:
        """``obsan lie``: the Lie derivatives of the outputs up to ``order``."""
        return self._run("lie", dict(order=order, input=input, set=set, **options))

    def check(self, modes: Union[str, Iterable[str]], input: Optional[str] = None, **options: Any) -> dict:
        """``obsan check``: candidate observable modes against eq. (11). A failed mode
        is a value (``checks[i]["observable_mode"]`` false), not an exception."""
        modes = [modes] if isinstance(modes, str) else list(modes)
        return self._run("check", dict(mode=modes, input=input, **options))


def load(path: PathLike) -> System:
    """Read a ``.sys`` file. Errors name the path, line and column."""
    return System(_path("load: path", path))


def loads(text: str) -> System:
    """A system from ``.sys`` text; errors read ``<string>:LINE:COL: ...``."""
    return System(STRING_NAME, _text("loads: text", text))


def simplify(expr: str, **options: Any) -> dict:
    """``obsan simplify``: the exact canonical form of ``expr``."""
    return _call(["simplify", _text("simplify: expr", expr), *_flags(options), "--json"])


def diff(expr: str, var: str, **options: Any) -> dict:
    """``obsan diff``: d expr / d var, in canonical form."""
    expr, var = _text("diff: expr", expr), _text("diff: var", var)
    return _call(["diff", expr, var, *_flags(options), "--json"])


def verify(path: PathLike, **options: Any) -> dict:
    """``obsan verify``: a decomposition file's exact checks (a failed check is a value)."""
    return _call(["verify", _path("verify: path", path), *_flags(options), "--json"])


def calibrate(
    dataset: PathLike,
    method: str = "ml",
    d0: Optional[float] = None,
    **options: Any,
) -> dict:
    """``obsan calibrate``: phi, psi, eta, delta, xi (and with ``d0`` rho, rR, rL, B)
    with standard deviations. ``method`` is det, ls, cekf or ml."""
    dataset, method = _path("calibrate: dataset", dataset), _text("calibrate: method", method)
    return _call(["calibrate", dataset, *_flags(dict(method=method, d0=d0, **options)), "--json"])


_SIM_JOIN = ("q",)


def crlb(dataset: Optional[PathLike] = None, **options: Any) -> dict:
    """``obsan crlb``: the Cramér–Rao bound for a dataset (at its ML estimate) or for
    a simulated set-up given by the :func:`simulate` options."""
    head = [_path("crlb: dataset", dataset)] if dataset is not None else []
    return _call(["crlb", *head, *_flags(options, join=_SIM_JOIN), "--json"])


def diagnose(
    model: Union[PathLike, System],
    data: PathLike,
    effects: Optional[PathLike] = None,
    **options: Any,
) -> dict:
    """``obsan diagnose``: fit ``model`` to ``data``, test the residuals, name the
    significant effects. ``model`` is a path or a :class:`System`."""
    source = None
    if isinstance(model, System):
        source, model = model._source, model.path
    model, data = _path("diagnose: model", model), _path("diagnose: data", data)
    if effects is not None:
        effects = _path("diagnose: effects", effects)
    argv = ["diagnose", "--model", model, "--data", data]
    # Generated candidates are on by default: ``generated=False`` must say so.
    if options.get("generated") is False:
        options = dict(options, generated=None, no_generated=True)
    argv += _flags(dict(effects=effects, **options))
    return _call([*argv, "--json"], source)


def simulate(out: PathLike, **options: Any) -> str:
    """``obsan simulate``: write the paper's simulated dataset (section VI-A) to the
    new folder ``out`` (``force=True`` replaces a folder obsan wrote) and return its
    path; the truth is in ``out/truth.json``. Options are the CLI's flags:
    ``q=[0.9, 0, -1]``, ``sigma_beta_deg``, ``bearings``, ``seed``,
    ``effect={"bearing_scale": 0.04}``, ..."""
    out = _path("simulate: out", out)
    run("simulate", "--out", out, *_flags(options, join=_SIM_JOIN))
    return os.fspath(out)


def montecarlo(**options: Any) -> Any:
    """``obsan montecarlo``: the paper's Tables IV–VII (``table=5``, ``runs=100``,
    ``cell=3``, ``seed=1``, ``threads=2``, ...) as a list of tables (see docs/montecarlo.md).

    With ``shard="K/N"`` (or ``shard=(K, N)``) it runs that fixed subset of the runs and
    returns the partial result, a plain dict (never numpy: it is meant for
    :func:`montecarlo_merge`, and ``json.dump`` writes it as ``obsan montecarlo merge``
    reads it)."""
    shard = options.get("shard")
    if isinstance(shard, (tuple, list)):
        options = dict(options, shard=f"{shard[0]}/{shard[1]}")
    argv = ["montecarlo", *_flags(options), "--json"]
    if shard is not None:
        return run(*argv).value
    return _call(argv)


def montecarlo_merge(parts: Iterable[Any]) -> Any:
    """``obsan montecarlo merge --json``: the partial results of every shard of one sweep
    (the dicts :func:`montecarlo` returns with ``shard=``, or paths of the files the CLI's
    ``--shard K/N --json`` wrote), in any order, as exactly the tables one run gives."""
    import tempfile

    parts = list(parts)
    with tempfile.TemporaryDirectory(prefix="obsan-merge-") as d:
        paths = []
        for i, p in enumerate(parts, 1):
            if isinstance(p, Mapping):
                path = os.path.join(d, f"part{i}.json")
                with open(path, "w", encoding="utf-8") as f:
                    json.dump(p, f)
                paths.append(path)
            else:
                paths.append(_path("montecarlo_merge: a part", p))
        return _call(["montecarlo", "merge", *paths, "--json"])
