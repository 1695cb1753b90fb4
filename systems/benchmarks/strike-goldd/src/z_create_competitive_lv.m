% Competitive Lotka-Volterra, two species, both measured (as STRIKE-GOLDD's cLV);
% written for obsan from the model's equations.
syms x1 x2 r1 r2 K1 K2 a12 a21
x = [x1; x2];
p = [r1; r2; K1; K2; a12; a21];
f = [r1*x1*(1 - (x1 + a12*x2)/K1);
     r2*x2*(1 - (x2 + a21*x1)/K2)];
h = [x1; x2];
