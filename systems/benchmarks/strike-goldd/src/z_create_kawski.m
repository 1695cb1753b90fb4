% Control example 1.1 of Kawski (accessible, not controllable), no parameters; written for
% obsan from its equations.
syms x1 x2 x3 x4 u
x = [x1; x2; x3; x4];
p = [];
u = [u];
f = [u;
     x1;
     x1^3;
     x3^2 - x2^8];
h = [x1;
     x2];
