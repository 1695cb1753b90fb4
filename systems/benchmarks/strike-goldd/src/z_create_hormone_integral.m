% Hormonal circuit with integral feedback (Karin et al., Mol Syst Biol 2016; Fig. 1A of
% Villaverde & Banga, arXiv:1701.02562); written for obsan from its equations.
syms x1 x2 p1 p2 u u0 x10
x = [x1; x2];
p = [p1; p2];
u = [u];
f = [u0 + u - p2*x1 - p1*x2;
     x1 - x10];
h = x1;
