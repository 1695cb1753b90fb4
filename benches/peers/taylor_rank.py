#!/usr/bin/env python3
"""Independent rank oracle for models too large for symbolic Lie derivatives (issue 32): SymPy
reads the model, NumPy does the arithmetic; nothing of obsan is used.

The observability-identifiability rank of x' = f(x, p, u), y = h(x, p) at t = 0 is the rank of
the Jacobian, in z = (x(0), p), of the outputs' Taylor coefficients y_k = y^(k)(0)/k!, k = 0, 1,
... (Sedoglavic, "A probabilistic algorithm to test local algebraic observability in polynomial
time", J. Symbolic Comput. 33(5), 2002: the same row space as the Lie derivatives' gradients).
The coefficients are computed modulo the prime P = 2^31 - 1 at a random point by power series
in t whose coefficients are dual numbers (a value and its N = dim z partial derivatives):
x_{k+1} = [f(x(t))]_k / (k + 1), order by order, every node of the expression graph carried
to order k before the states' next coefficient (products by Cauchy sums, quotients by the
division recurrence, log(s) by s L' = s'). Known inputs get random Taylor coefficients.

Exactness. A rank r at the point is a lower bound for the generic rank, **exactly**: an r x r
minor that is non-zero modulo P at the point is a non-zero rational function over Q. So r = N
proves the model weakly locally observable. A rank below N is the generic rank unless the point
is unlucky (a proper algebraic subset); the script then says so, and an upper bound must come
from elsewhere (a symmetry derived by hand). `log` is accepted of a single state or param only:
log x_1, ..., log x_n are algebraically independent over Q(x) (so their values at the point are
drawn as independent random numbers, each with the derivative 1/x_i of the chain rule), and the
rank over the functions of (x, p) equals the rank over independent (x, p, log x). Other
transcendental functions and non-integer powers are refused.

Stopping. Without inputs, an order that raises no rank ends the computation (the codistribution
of the Lie derivatives is then invariant under f); with inputs the script runs to --orders.
A variable is observable (at the point) when its unit covector lies in the row space.

Usage: taylor_rank.py [--orders K] [--seed S] MODEL.sys ...   (prints one '# verdict:' line each)
"""

import argparse
import random
import sys
import time

import numpy as np
import sympy as sp

sys.path.insert(0, __file__.rsplit("/", 1)[0])
from sg_verdicts import read_sys  # noqa: E402  (the same plain .sys subset, its own parser)

P = 2147483647


def inv(a):
    a = int(a) % P
    if a == 0:
        raise ZeroDivisionError("a denominator vanishes at the point: try another --seed")
    return pow(a, P - 2, P)


def num_mod(q):
    q = sp.Rational(q)
    return int(q.p) % P * inv(q.q) % P


class Graph:
    """Nodes of the expressions, children before parents (as obsan's arena, independently)."""

    def __init__(self):
        self.ops, self.memo = [], {}

    def add(self, op):
        if op not in self.memo:
            self.memo[op] = len(self.ops)
            self.ops.append(op)
        return self.memo[op]

    def of(self, e, leaf):
        if e in leaf:
            return leaf[e]
        if e.is_Number:
            return self.add(("num", num_mod(e)))
        if e.is_Add:
            ids = [self.of(a, leaf) for a in e.args]
            acc = ids[0]
            for b in ids[1:]:
                acc = self.add(("add", acc, b))
            return acc
        if e.is_Mul:
            num, den = [], []
            for a in e.args:
                if a.is_Pow and a.exp.is_Integer and a.exp < 0:
                    den.append(self.of(a.base**-a.exp, leaf))
                else:
                    num.append(self.of(a, leaf))
            acc = num[0] if num else self.add(("num", 1))
            for b in num[1:]:
                acc = self.add(("mul", acc, b))
            for b in den:
                acc = self.add(("div", acc, b))
            return acc
        if e.is_Pow and e.exp.is_Integer:
            n = int(e.exp)
            base = self.of(e.base, leaf)
            if n < 0:
                return self.add(("div", self.add(("num", 1)), self.of(e.base**-n, leaf)))
            acc, sq, first = None, base, True
            while n:
                if n & 1:
                    acc = sq if first else self.add(("mul", acc, sq))
                    first = False
                n >>= 1
                if n:
                    sq = self.add(("mul", sq, sq))
            return acc
        if isinstance(e, sp.log) and e.args[0] in leaf:
            return self.add(("log", leaf[e.args[0]]))
        raise ValueError(f"not supported by this oracle: {e}")


def dmul(a, b):
    """Dual products of rows a[i], b[i] (value in column 0), summed over i, modulo P."""
    v = (a[:, 0] * b[:, 0]) % P
    d = (a[:, :1] * b[:, 1:]) % P + (b[:, :1] * a[:, 1:]) % P
    out = np.empty(a.shape[1], dtype=np.int64)
    out[0] = v.sum() % P
    out[1:] = d.sum(axis=0) % P
    return out


def ddiv(u, v):
    """The dual number u / v."""
    i0 = inv(v[0])
    q0 = u[0] * i0 % P
    out = np.empty_like(u)
    out[0] = q0
    out[1:] = (u[1:] - q0 * v[1:] % P) % P * i0 % P
    return out


def verdict(path, orders, seed):
    decl, x, p, u, rhs, h, consts = read_sys(path)
    if any(g.has(ui) for g in h for ui in u):
        raise ValueError("an output reads an input: use sg_verdicts.py")
    z = x + p
    n, N = len(x), len(x) + len(p)
    rng = random.Random(seed)
    g = Graph()
    leaf = {}
    for s in z + u + consts:
        leaf[s] = g.add(("leaf", str(s)))
    fid = [g.of(e, leaf) for e in rhs]
    hid = [g.of(e, leaf) for e in h]
    K = orders
    W = N + 1
    c = np.zeros((len(g.ops), K + 1, W), dtype=np.int64)
    # order 0: the point; z's derivatives are the unit vectors, inputs' and constants' zero
    for j, s in enumerate(z):
        c[leaf[s], 0, 0] = rng.randrange(2, P - 1)
        c[leaf[s], 0, 1 + j] = 1
    for s in consts:
        c[leaf[s], 0, 0] = rng.randrange(2, P - 1)
    for s in u:
        c[leaf[s], :, 0] = [rng.randrange(2, P - 1) for _ in range(K + 1)]
    logv = {}
    rows, piv = [], []  # the row space, in echelon form (pivot columns)
    kept = 0

    def reduce(r):
        r = r.copy()
        for row, col in zip(rows, piv):
            if r[col]:
                r = (r - r[col] * row) % P
        nz = np.nonzero(r)[0]
        return r, (nz[0] if len(nz) else None)

    def keep(r):
        r, col = reduce(r)
        if col is None:
            return False
        r = r * inv(r[col]) % P
        for i, row in enumerate(rows):
            if row[col]:
                rows[i] = (row - row[col] * r) % P
        rows.append(r)
        piv.append(col)
        return True

    used = 0
    for k in range(K + 1):
        for i, op in enumerate(g.ops):
            kind = op[0]
            if kind == "leaf":
                continue  # states' coefficients are set below, the rest at order 0
            if kind == "num":
                if k == 0:
                    c[i, 0, 0] = op[1]
            elif kind == "add":
                c[i, k] = (c[op[1], k] + c[op[2], k]) % P
            elif kind == "mul":
                c[i, k] = dmul(c[op[1], : k + 1], c[op[2], k::-1])
            elif kind == "div":
                a, b = c[op[1]], c[op[2]]
                acc = a[k].copy()
                if k:
                    acc = (acc - dmul(b[1 : k + 1], c[i, k - 1 :: -1][:k])) % P
                c[i, k] = ddiv(acc, b[0])
            elif kind == "log":
                s = c[op[1]]
                if k == 0:
                    if op[1] not in logv:
                        logv[op[1]] = rng.randrange(2, P - 1)
                    # an independent value; the chain rule's derivative ds/s
                    c[i, 0, 0] = logv[op[1]]
                    c[i, 0, 1:] = s[0, 1:] * inv(s[0, 0]) % P
                else:
                    acc = k * s[k] % P
                    if k > 1:
                        ks = (np.arange(1, k)[:, None] * c[i, 1:k]) % P
                        acc = (acc - dmul(ks, s[k - 1 : 0 : -1])) % P
                    c[i, k] = ddiv(acc, s[0]) * inv(k) % P
        # the outputs' coefficient k, then the states' coefficient k + 1
        before = len(rows)
        for j in hid:
            if len(rows) < N:
                keep(c[j, k, 1:])
        used = k
        if len(rows) == N or (not u and k > 0 and len(rows) == before):
            break
        if k < K:
            ik = inv(k + 1)
            for j, fi in enumerate(fid):
                c[leaf[x[j]], k + 1] = c[fi, k] * ik % P
    rank = len(rows)
    names = [str(s) for s in z]
    unobs = []
    for j in range(N):
        e = np.zeros(N, dtype=np.int64)
        e[j] = 1
        if reduce(e)[1] is not None:
            unobs.append(names[j])
    exact = "exact (full rank at a point)" if rank == N else "at one point (a lower bound, exact)"
    if rank < N and used == K:
        exact += f"; stopped at --orders {K}"
    return rank, N, unobs, used, exact


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--orders", type=int, default=60)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("files", nargs="+")
    a = ap.parse_args()
    for f in a.files:
        t = time.perf_counter()
        try:
            rank, N, unobs, used, how = verdict(f, a.orders, a.seed)
        except (ValueError, ZeroDivisionError) as e:
            print(f"{f}: none: {e}")
            continue
        dt = time.perf_counter() - t
        v = f"unobservable {' '.join(unobs)}" if unobs else "observable"
        print(f"{f}: rank {rank} of {N}, Taylor orders 0..{used}, {how}, {dt:.1f} s")
        print(f"# verdict: {v}; rank {rank}")


if __name__ == "__main__":
    main()
