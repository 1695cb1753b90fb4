#!/usr/bin/env python3
"""Write the beta-cell / insulin / glucose ("BIG") model variants of the STRIKE-GOLDD suite
(systems/benchmarks/strike-goldd/src/z_create_big_out_O_par_P.m) from the model's equations.

The model: Topp et al., J. Theor. Biol. 206:605-619 (2000), with the beta-cell turnover of Karin
et al., Mol. Syst. Biol. 12:886 (2016); the variants (which outputs are measured, which
parameters are unknown) are those of Villaverde & Banga, arXiv:1701.02562 (Fig. 1D), as
STRIKE-GOLDD's library names them. Glucose G = x1, beta-cell mass B = x2, insulin I = x3; a
known glucose input u and constant intake u0;
  G' = u0 + u - (p4 + p2 I) G
  B' = B (mu+ / (1 + (8.4/G)^1.7) - mu- / (1 + (G/4.8)^8.5)),  mu+ = 0.021/1440, mu- = 0.025/1440
  I' = p1 B G^2 / (p5^2 + G^2) - p3 I.
Outputs O: any of B, G, I (B, G, I, BG, BI, GI, BIG); unknown parameters P: s = {p2},
ps = {p1, p2}, agcs = {p2, p3, p4, p5}, agcsp = {p1..p5}; the others are known constants.
No STRIKE-GOLDD text is used (it is GPL-3). Usage: python3 scripts/write_big_variants.py
"""

import os

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SRC = os.path.join(ROOT, "systems", "benchmarks", "strike-goldd", "src")
OUTPUTS = {"b": ["x2"], "g": ["x1"], "i": ["x3"], "bg": ["x1", "x2"], "bi": ["x2", "x3"],
           "gi": ["x1", "x3"], "big": ["x1", "x2", "x3"]}
PARAMS = {"s": ["p2"], "ps": ["p1", "p2"], "agcs": ["p2", "p3", "p4", "p5"],
          "agcsp": ["p1", "p2", "p3", "p4", "p5"]}
NAMES = {"x1": "glucose", "x2": "beta-cell mass", "x3": "insulin"}


def text(o, p):
    outs, unknown = OUTPUTS[o], PARAMS[p]
    known = [q for q in ["p1", "p2", "p3", "p4", "p5"] if q not in unknown]
    return "\n".join([
        f"% Beta-cell mass, insulin and glucose (BIG; Topp et al., J. Theor. Biol. 206:605-619, 2000;",
        "% turnover rates of Karin et al., Mol. Syst. Biol. 12:886, 2016), the variant of Villaverde",
        f"% & Banga, arXiv:1701.02562, Fig. 1D measuring {', '.join(NAMES[x] for x in outs)} with",
        f"% {', '.join(unknown)} unknown ({', '.join(known) or 'none'} and u0 known); written for obsan",
        "% from its equations by scripts/write_big_variants.py.",
        "syms x1 x2 x3 u u0 p1 p2 p3 p4 p5",
        "x = [x1; x2; x3];",
        f"p = [{'; '.join(unknown)}];",
        "u = u;",
        "f = [u0 + u - (p4 + p2*x3)*x1;",
        "     x2*(0.021/1440/(1 + (8.4/x1)^1.7) - 0.025/1440/(1 + (x1/4.8)^8.5));",
        "     p1*x2*x1^2/(p5^2 + x1^2) - p3*x3];",
        f"h = [{'; '.join(outs)}];",
        "",
    ])


def main():
    for o in OUTPUTS:
        for p in PARAMS:
            with open(os.path.join(SRC, f"z_create_big_out_{o}_par_{p}.m"), "w", encoding="utf-8") as f:
                f.write(text(o, p))


if __name__ == "__main__":
    main()
