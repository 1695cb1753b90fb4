#!/bin/sh
# Oracle for `obsan global` on the small hand-derived cases: Singular (Debian
# package `singular`) counts over Q from the Lie derivatives (lie_count.sing);
# obsan counts over F_p from the Taylor prolongation. Run from the repository
# root after `cargo build --release`; prints both and exits 1 on a mismatch.
# Tests/benches only: obsan never calls Singular.
set -eu
OBSAN=${OBSAN:-target/release/obsan}
dir=$(dirname "$0")
fail=0
case_() { # name, sys file, Singular ring/F/h/names/pt/K definitions
  name=$1; sys=$2; defs=$3
  sing=$(printf '%s\n< "%s/lie_count.sing";\n' "$defs" "$dir" | Singular -q 2>&1 | sort)
  ob=$("$OBSAN" global "$sys" --json | python3 -c '
import json, sys
v = json.load(sys.stdin)
print("joint", v["solutions"])
for x in v["variables"]:
    print(x["name"], x["values"])' | sort)
  if [ "$sing" = "$ob" ]; then echo "$name: agree"; else
    echo "$name: MISMATCH"; echo "Singular:"; echo "$sing"; echo "obsan:"; echo "$ob"; fail=1; fi
}
case_ squared_rate systems/global/squared_rate.sys '
ring r = 0, (x, a), dp; ideal F = -a^2*x, 0; ideal H = x;
list vn = "x", "a"; intvec pt = 3, 5; int K = 2;'
case_ single_decay systems/global/single_decay.sys '
ring r = 0, (x, a), dp; ideal F = -a*x, 0; ideal H = x;
list vn = "x", "a"; intvec pt = 3, 5; int K = 2;'
case_ two_decays systems/global/two_decays.sys '
ring r = 0, (x1, x2, a, b), dp; ideal F = -a*x1, -b*x2, 0, 0; ideal H = x1 + x2;
list vn = "x1", "x2", "a", "b"; intvec pt = 3, 7, 2, 11; int K = 5;'
# Xia and Moog's HIV model, outputs T and V: (delta, c) is an unordered pair.
case_ hiv_xia_moog systems/classic/hiv.sys '
ring r = 0, (T, I, V, s, d, beta, delta, p, c), dp;
ideal F = s - d*T - beta*T*V, beta*T*V - delta*I, p*I - c*V, 0, 0, 0, 0, 0, 0;
ideal H = T, V;
list vn = "T", "I", "V", "s", "d", "beta", "delta", "p", "c";
intvec pt = 3, 5, 7, 2, 11, 13, 17, 19, 23; int K = 5;'
exit $fail
