% Pitavastatin uptake with a pseudo-steady-state assumption (Grandjean, Chappell, Yates, Evans,
% 2014, eqs. (109)-(110)); written for obsan from its equations.
syms x1 x3 r3 k3 k4 Vm Km T0 k
x = [x1; x3];
p = [r3; k3; k4; Vm; Km; T0];
f = [k3*x3 - r3*x1 - Vm*x1/(Km + x1);
     r3*x1 - (k3 + k4)*x3 + Vm*x1/(Km + x1)];
h = k*(T0*x1/(Km + x1) + x3);
