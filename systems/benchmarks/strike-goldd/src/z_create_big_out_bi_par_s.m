% Beta-cell mass, insulin and glucose (BIG; Topp et al., J. Theor. Biol. 206:605-619, 2000;
% turnover rates of Karin et al., Mol. Syst. Biol. 12:886, 2016), the variant of Villaverde
% & Banga, arXiv:1701.02562, Fig. 1D measuring beta-cell mass, insulin with
% p2 unknown (p1, p3, p4, p5 and u0 known); written for obsan
% from its equations by scripts/write_big_variants.py.
syms x1 x2 x3 u u0 p1 p2 p3 p4 p5
x = [x1; x2; x3];
p = [p2];
u = u;
f = [u0 + u - (p4 + p2*x3)*x1;
     x2*(0.021/1440/(1 + (8.4/x1)^1.7) - 0.025/1440/(1 + (x1/4.8)^8.5));
     p1*x2*x1^2/(p5^2 + x1^2) - p3*x3];
h = [x2; x3];
