#!/usr/bin/env python3
"""Independent verdicts for systems/benchmarks/strike-goldd/ (issue 32): SymPy, not obsan.

For each .sys file given, reads the states, params, inputs, equations and outputs (the plain
subset the importers write), and computes the observability-identifiability rank with the
inputs free (an input an output reads is measured, its derivative known: see verdict()): the span of the gradients (in states and params) of the outputs' Lie derivatives
along every word of the fields f0, f_1..f_m (the input-affine form, f_i = d rhs / d u_i),
level by level until a level adds no rank (then no later level does); only the functions
that raised the rank are carried to the next level (see verdict()). The Jacobian is
evaluated exactly at a random integer point (entries 2..1000): a rank below the generic one
happens only on a proper algebraic subset, i.e. with small probability; a variable is
observable when its unit vector lies in the row span. Prints one '# verdict:' line per file.

Usage: python3 benches/peers/sg_verdicts.py [--list] [--timeout S] systems/benchmarks/strike-goldd/*.sys

--digits D evaluates the Jacobian in floating point with D significant digits (mpmath) instead
of exactly, for models whose exact algebraic numbers SymPy cannot rank in time (the BIG models'
rational exponents: `(8.4/x1)^1.7` at an integer point is a product of radicals): the roots
take their real positive values, and a singular value below 10^(-D/3) of the largest counts
as zero; the gap between the two is printed to stderr, so a verdict resting on a small gap can
be seen. An independent computation (symbolic Lie derivatives, real arithmetic), not a proof.

--list prints `NAME<TAB>SPEC` lines for verdicts.list instead; --timeout S gives up on a file
after S seconds of SymPy (wall clock), and then prints `NAME<TAB>none: ...` in place of a
verdict (the suite file then says `verdict-source: none`; never a verdict from obsan).
"""

import keyword
import os
import random
import re
import signal
import sys

import sympy as sp


def read_sys(path):
    decl = {"state": [], "param": [], "input": [], "const": []}
    eqs, outs = {}, []
    for raw in open(path, encoding="utf-8"):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        m = re.match(r"^(state|param|input|const)\s+(.*)$", line)
        if m:
            decl[m.group(1)] += [n.strip() for n in m.group(2).split(",")]
            continue
        m = re.match(r"^output\s+(\w+)\s*=\s*(.*)$", line)
        if m:
            outs.append(m.group(2))
            continue
        m = re.match(r"^(\w+)'\s*=\s*(.*)$", line)
        if m:
            eqs[m.group(1)] = m.group(2)
    names = {n: sp.Symbol(n) for k in decl for n in decl[k]}
    # A model name that is a Python keyword (`lambda`) is parsed under an alias.
    kw = {n for n in names if keyword.iskeyword(n)}
    local = {(f"{n}_kw_" if n in kw else n): v for n, v in names.items()}
    alias = lambda s: re.sub(r"\b(\w+)\b", lambda m: f"{m[1]}_kw_" if m[1] in kw else m[1], s)
    # rational=True: a decimal such as 2.265 is read as the exact 453/200, so the rank is exact.
    parse = lambda s: sp.sympify(alias(s).replace("^", "**"), locals=local, rational=True)
    x = [names[n] for n in decl["state"]]
    p = [names[n] for n in decl["param"]]
    u = [names[n] for n in decl["input"]]
    rhs = [parse(eqs[n]) for n in decl["state"]]
    h = [parse(o) for o in outs]
    return decl, x, p, u, rhs, h, [names[n] for n in decl["const"]]


DIGITS = 0


def numeric_rank(rows):
    """Numerical rank of mpmath rows at DIGITS digits, the smallest kept and the largest dropped
    singular value, each relative to the largest."""
    import mpmath

    if not rows:
        return 0, None, None
    sv = sorted(mpmath.svd_r(mpmath.matrix(rows), compute_uv=False), reverse=True)
    tol = sv[0] * mpmath.mpf(10) ** (-(DIGITS // 3))
    r = sum(1 for v in sv if v > tol)
    kept = sv[r - 1] / sv[0] if r else None
    dropped = sv[r] / sv[0] if r < len(sv) else None
    return r, kept, dropped


def verdict(path, seed=1):
    """Rank of the observability codistribution at a random integer point, and the variables
    whose unit covector lies outside it. Only the functions whose gradient raised the rank are
    differentiated further: if dphi lies in the span of kept gradients (coefficients functions
    c_i), L_f(sum c_i dphi_i) = sum (L_f c_i) dphi_i + c_i d(L_f phi_i) lies in the span of the
    kept ones and their Lie derivatives, so the next level needs only the new functions."""
    decl, x, p, u, rhs, h, consts = read_sys(path)
    # Inputs read by an output: each is taken as measured with its derivative known (as
    # STRIKE-GOLDD's nnzDerU = 1): the input is a coordinate v with v' = dv, dv a new free
    # input whose field is the unit vector of v, the terms f_v v stay in the drift, and v is
    # an extra output (its gradient dv is then in the span). The verdict is about x and p:
    # the rank minus one per such input, the unobservable list over x and p only.
    read = [ui for ui in u if any(g.has(ui) for g in h)]
    free = [ui for ui in u if ui not in read]
    xa = x + read
    z = xa + p
    pad = [sp.Integer(0)] * len(read)
    f0 = [r.subs({ui: 0 for ui in free}) for r in rhs] + pad
    fields = [f0] + [[sp.diff(r, ui) for r in rhs] + pad for ui in free]
    for i in range(len(read)):
        unit = [sp.Integer(1) if k == i else sp.Integer(0) for k in range(len(read))]
        fields.append([sp.Integer(0)] * len(rhs) + unit)
    rng = random.Random(seed)
    point = {s: sp.Integer(rng.randint(2, 1000)) for s in z + consts}
    arith = Numeric(z, consts, point) if DIGITS else Exact(z, point)
    rows, level = [], []
    for g in list(read) + h:
        if arith.keep(rows, arith.row(g)):
            level.append(g)
    while level and len(rows) < len(z):
        nxt = []
        for g in level:
            for fld in fields:
                lg = sum(sp.diff(g, xi) * fi for xi, fi in zip(xa, fld))
                if lg != 0 and arith.keep(rows, arith.row(lg)):
                    nxt.append(lg)
        level = nxt
    rank = len(rows) - len(read)
    unobs = [
        str(v)
        for j, v in enumerate(z)
        if v not in read and arith.rank(rows + [arith.unit(j)]) > len(rows)
    ]
    arith.report(rank)
    if unobs:
        return f"unobservable {' '.join(unobs)}; rank {rank}"
    return f"observable; rank {rank}"


class Exact:
    """Gradients at the point in exact rationals (SymPy)."""

    def __init__(self, z, point):
        self.z, self.point = z, point

    def row(self, g):
        return [sp.diff(g, v).subs(self.point) for v in self.z]

    def unit(self, j):
        return [1 if k == j else 0 for k in range(len(self.z))]

    def rank(self, rows):
        return sp.Matrix(rows).rank() if rows else 0

    def keep(self, rows, row):
        """Append row to rows when it raises their rank; say whether it did."""
        if self.rank(rows + [row]) > len(rows):
            rows.append(row)
            return True
        return False

    def report(self, rank):
        pass


class Numeric(Exact):
    """Gradients at the point in mpmath at DIGITS digits; ranks by singular values, the worst
    gap seen reported on stderr."""

    def __init__(self, z, consts, point):
        import mpmath

        mpmath.mp.dps = DIGITS
        super().__init__(z, point)
        self.syms = z + consts
        self.vals = [mpmath.mpf(int(point[s])) for s in self.syms]
        self.kept, self.dropped = mpmath.mpf(1), mpmath.mpf(0)

    def row(self, g):
        import mpmath

        grad = [sp.diff(g, v) for v in self.z]
        return [mpmath.mpf(v) for v in sp.lambdify(self.syms, grad, "mpmath")(*self.vals)]

    def unit(self, j):
        import mpmath

        return [mpmath.mpf(1 if k == j else 0) for k in range(len(self.z))]

    def rank(self, rows):
        r, kept, dropped = numeric_rank(rows)
        if kept is not None:
            self.kept = min(self.kept, kept)
        if dropped is not None:
            self.dropped = max(self.dropped, dropped)
        return r

    def report(self, rank):
        import mpmath

        print(
            f"  rank {rank}: smallest singular value kept {mpmath.nstr(self.kept, 3)}, "
            f"largest dropped {mpmath.nstr(self.dropped, 3)} (relative to the largest)",
            file=sys.stderr,
        )


class Timeout(Exception):
    pass


def on_alarm(_sig, _frame):
    raise Timeout()


def main(args):
    listing, timeout = False, 0
    while args and args[0].startswith("--"):
        if args[0] == "--list":
            listing, args = True, args[1:]
        elif args[0] == "--digits" and len(args) > 1:
            global DIGITS
            DIGITS, args = int(args[1]), args[2:]
        elif args[0] == "--timeout" and len(args) > 1:
            timeout, args = int(args[1]), args[2:]
        else:
            sys.exit(f"unknown option {args[0]}")
    signal.signal(signal.SIGALRM, on_alarm)
    for path in args:
        name = os.path.basename(path)[: -len(".sys")]
        signal.alarm(timeout)
        try:
            spec = verdict(path)
        except Timeout:
            spec = None
        signal.alarm(0)
        if listing and spec is None:
            print(f"{name}\tnone: SymPy did not finish within {timeout} s", flush=True)
        elif listing and DIGITS:
            print(f"{name}\tmpmath {DIGITS}: {spec}", flush=True)
        elif listing:
            print(f"{name}\t{spec}", flush=True)
        elif spec is None:
            print(f"{path}\t# verdict-source: none (SymPy did not finish within {timeout} s)", flush=True)
        else:
            print(f"{path}\t# verdict: {spec}", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
