#!/usr/bin/env python3
"""Write the Monod species-metabolite interaction models (MSMI) of the STRIKE-GOLDD suite
(systems/benchmarks/strike-goldd/src/z_create_msmi_NxMm_hOUTS.m) from the model's equations.

The model (Diaz-Seoane, Sellan, Villaverde, "Structural identifiability and observability of
microbial community models"; STRIKE-GOLDD's models/z_create_MSMI.m holds the same 53 variants):
species x_i grow on metabolites m_l with Monod-type kinetics, metabolites are consumed, fed and
produced:
  x_i' = x_i (sum_l v_il m_l / (k_il + m_l x_i) - d_i)
  m_l' = -m_l (sum_i vas_il x_i / (kas_il + m_l x_i) + s das_l) + f_l
         + sum_{i,j} phi_lij x_i m_j / (kas_ij + x_i m_j)
with s = -1 in the one-metabolite model and s = +1 in the others, as the source writes them.
Three communities: two species and one metabolite (2x1m), two and two (2x2m), three and two
(3x2m); each with every non-empty set of measured variables (7 + 15 + 31 = 53 files).
No STRIKE-GOLDD text is used (it is GPL-3). Usage: python3 scripts/write_msmi_variants.py
"""

import itertools
import os

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SRC = os.path.join(ROOT, "systems", "benchmarks", "strike-goldd", "src")
# (species, metabolites, sign of das in m_l')
COMMUNITIES = {"2x1m": (2, 1, -1), "2x2m": (2, 2, 1), "3x2m": (3, 2, 1)}


def model(ns, nm, sign):
    xs = [f"x{i}" for i in range(1, ns + 1)]
    ms = [f"m{l}" for l in range(1, nm + 1)]
    pairs = [(i, l) for l in range(1, nm + 1) for i in range(1, ns + 1)]
    params = ([f"v{i}{l}" for i, l in pairs] + [f"k{i}{l}" for i, l in pairs]
              + [f"d{i}" for i in range(1, ns + 1)] + [f"vas{i}{l}" for i, l in pairs]
              + [f"kas{i}{l}" for i, l in pairs] + [f"f{l}" for l in range(1, nm + 1)]
              + [f"das{l}" for l in range(1, nm + 1)]
              + [f"phi{l}{i}{j}" for l in range(1, nm + 1) for i, j in pairs])
    f = []
    for i in range(1, ns + 1):
        growth = " + ".join(f"v{i}{l}*m{l}/(k{i}{l} + m{l}*x{i})" for l in range(1, nm + 1))
        f.append(f"x{i}*({growth} - d{i})")
    for l in range(1, nm + 1):
        uptake = " + ".join(f"vas{i}{l}*x{i}/(kas{i}{l} + m{l}*x{i})" for i in range(1, ns + 1))
        das = f"+ das{l}" if sign > 0 else f"- das{l}"
        prod = " + ".join(f"phi{l}{i}{j}*x{i}*m{j}/(kas{i}{j} + x{i}*m{j})" for i, j in pairs)
        f.append(f"-m{l}*({uptake} {das}) + f{l} + {prod}")
    return xs + ms, params, f


def main():
    count = 0
    for name, (ns, nm, sign) in COMMUNITIES.items():
        states, params, f = model(ns, nm, sign)
        for r in range(len(states), 0, -1):
            for outs in itertools.combinations(states, r):
                lines = [
                    "% Species-metabolite interaction with Monod kinetics (Diaz-Seoane, Sellan, Villaverde,",
                    "% Structural identifiability and observability of microbial community models), "
                    f"{ns} species",
                    f"% and {nm} metabolite{'s' if nm > 1 else ''}, measuring {', '.join(outs)}; "
                    "written for obsan from its equations by",
                    "% scripts/write_msmi_variants.py.",
                    "syms " + " ".join(states + params),
                    f"x = [{'; '.join(states)}];",
                    f"p = [{'; '.join(params)}];",
                    "f = [" + ";\n     ".join(f) + "];",
                    f"h = [{'; '.join(outs)}];",
                    "",
                ]
                path = os.path.join(SRC, f"z_create_msmi_{name}_h{''.join(outs)}.m")
                with open(path, "w", encoding="utf-8") as out:
                    out.write("\n".join(lines))
                count += 1
    print(f"wrote {count} files")


if __name__ == "__main__":
    main()
