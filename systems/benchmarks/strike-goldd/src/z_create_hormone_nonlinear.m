% Nonlinear hormonal circuit with dynamical compensation (Karin et al., Mol Syst Biol 2016;
% Fig. 1C of Villaverde & Banga, arXiv:1701.02562); written for obsan from its equations.
syms x1 x2 x3 p1 p2 u u0 x10
x = [x1; x2; x3];
p = [p1; p2];
u = [u];
f = [u0 + u - p2*x1*x3;
     x2*(x1 - x10);
     p1*x2*x1 - x3];
h = x1;
