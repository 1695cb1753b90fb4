% Two-compartment pharmacokinetics, dose into and sampling from the central compartment
% (as STRIKE-GOLDD's C2M with known input); written for obsan from the model's equations.
syms x1 x2 k12 k21 k10 b u
x = [x1; x2];
p = [k12; k21; k10; b];
u = u;
f = [-(k12 + k10)*x1 + k21*x2 + b*u;
     k12*x1 - k21*x2];
h = x1;
