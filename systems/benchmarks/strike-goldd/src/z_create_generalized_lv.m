% Generalized Lotka-Volterra, three species, all measured (as STRIKE-GOLDD's gLV):
% xi' = xi (ri + sum_j aij xj); written for obsan from the model's equations.
syms x1 x2 x3 r1 r2 r3 a11 a12 a13 a21 a22 a23 a31 a32 a33
x = [x1 x2 x3].';
p = [r1 r2 r3 a11 a12 a13 a21 a22 a23 a31 a32 a33].';
f = [x1*(r1 + a11*x1 + a12*x2 + a13*x3);
     x2*(r2 + a21*x1 + a22*x2 + a23*x3);
     x3*(r3 + a31*x1 + a32*x2 + a33*x3)];
h = x;
