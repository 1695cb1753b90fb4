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
case_() { # name, sys file, Singular ring/F/h/names/pt/K definitions[, script, obsan flags]
  name=$1; sys=$2; defs=$3; script=${4:-lie_count.sing}; flags=${5:-}
  sing=$(printf '%s\n< "%s/%s";\n' "$defs" "$dir" "$script" | Singular -q 2>&1 | sort)
  ob=$("$OBSAN" global "$sys" $flags --json | python3 -c '
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
# The same cases by obsan's Lie route (a different polynomial system).
case_ two_decays_lie systems/global/two_decays.sys '
ring r = 0, (x1, x2, a, b), dp; ideal F = -a*x1, -b*x2, 0, 0; ideal H = x1 + x2;
list vn = "x1", "x2", "a", "b"; intvec pt = 3, 7, 2, 11; int K = 5;' lie_count.sing "--route lie"
case_ hiv_xia_moog_lie systems/classic/hiv.sys '
ring r = 0, (T, I, V, s, d, beta, delta, p, c), dp;
ideal F = s - d*T - beta*T*V, beta*T*V - delta*I, p*I - c*V, 0, 0, 0, 0, 0, 0;
ideal H = T, V;
list vn = "T", "I", "V", "s", "d", "beta", "delta", "p", "c";
intvec pt = 3, 5, 7, 2, 11, 13, 17, 19, 23; int K = 5;' lie_count.sing "--route lie"
# With an input (every word over the fields, obsan's Lie route): the cart of
# systems/global/squared_range_gain.sys, (x, a) up to a common sign.
case_ squared_range_gain systems/global/squared_range_gain.sys '
ring r = 0, (x, a), dp; list FS = ideal(a, 0); ideal H = x^2;
list vn = "x", "a"; intvec pt = 3, 5; int K = 3;' lie_words.sing "--route lie"
exit $fail
