% Generalized Lotka-Volterra, three species, relative abundance of species 3 measured
% (Diaz-Seoane, Sellan, Villaverde, Structural identifiability and observability of microbial
% community models); written for obsan from its equations.
syms x1 x2 x3 r1 r2 r3 beta11 beta12 beta13 beta21 beta22 beta23 beta31 beta32 beta33
x = [x1; x2; x3];
p = [r1; r2; r3; beta11; beta12; beta13; beta21; beta22; beta23; beta31; beta32; beta33];
f = [r1*x1 + beta11*x1^2 + beta12*x1*x2 + beta13*x1*x3;
     r2*x2 + beta21*x1*x2 + beta22*x2^2 + beta23*x2*x3;
     r3*x3 + beta31*x1*x3 + beta32*x2*x3 + beta33*x3^2];
h = x3/(x1 + x2 + x3);
