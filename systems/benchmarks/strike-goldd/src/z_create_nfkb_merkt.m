% NF-kB transcription factor with an input-affine stimulus (Merkt et al., Phys. Rev. E 92,
% 2015; the input-affine form in STRIKE-GOLDD's NLcontr_models); written for obsan from its
% equations.
syms x1 x2 x3 x4 x5 x6 x7 x8 x9 x10 s1 s2 s3 s4 k1p k1 k2 k3 k4 k5 k6 k7 k8 k9 k10 k11 rhovol ...
     I0cyt I0nuc u0
x = [x1; x2; x3; x4; x5; x6; x7; x8; x9; x10];
p = [s1; s2; s3; s4; k1p; k1; k2; k3; k4; k5; k6; k7; k8; k9; k10; k11; rhovol; I0cyt; I0nuc];
u = [u0];
f = [k11*x10 - (k1*u0 + k1p)*x1;
     (k1*u0 + k1p)*x1 - k2*x2;
     k2*x2 - k3*x3;
     k2*x2 - k4*x4;
     k3*rhovol*x3 - k5*x5;
     k5*x5 - k10*x9*x6;
     k6*x6 - k7*x7;
     k8*x7 - k9*x8;
     k9*rhovol*x8 - k10*x9*x6;
     k10*x9*x6 - k11*rhovol*x10];
h = [s1*(x1 + x2 + x3) + I0cyt;
     s2*(x10 + x5 + x6) + I0nuc;
     s3*(x2 + x3);
     s4*(x2 + x4)];
