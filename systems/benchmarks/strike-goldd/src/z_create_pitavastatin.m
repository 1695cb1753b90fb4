% Pitavastatin hepatic uptake, three states (Grandjean, Chappell, Yates, Evans, Structural
% identifiability analyses of candidate models for in vitro Pitavastatin hepatic uptake, Comput
% Methods Programs Biomed 114(3), 2014); written for obsan from its equations.
syms x1 x2 x3 k1 k2 k3 k4 r1 r3 T0 k
x = [x1; x2; x3];
p = [k1; k2; k3; k4; r1; r3; T0];
f = [k3*x3 - r3*x1 - k1*x1*(T0 - x2) + r1*x2;
     k1*x1*(T0 - x2) - (r1 + k2)*x2;
     r3*x1 - (k3 + k4)*x3 + k2*x2];
h = k*(x2 + x3);
