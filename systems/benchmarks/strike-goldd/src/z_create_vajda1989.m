% Unidentifiable nonlinear compartmental model with a known input (Vajda, Godfrey, Rabitz,
% Similarity transformation approach to identifiability analysis of nonlinear compartmental
% models, Math. Biosci. 1989); written for obsan from its equations.
syms x1 x2 t1 t2 t3 t4 u1
x = [x1; x2];
p = [t1; t2; t3; t4];
u = [u1];
f = [t1*x1^2 + t2*x1*x2 + u1;
     t3*x1^2 + t4*x1*x2];
h = x1;
