% Chemical reaction model, one state (Merkt et al. 2015, Higher-order Lie symmetries in
% identifiability and predictability analysis of dynamic models, Phys. Rev. E 92); written for
% obsan from its equations.
syms x1 k s1 s2
x = [x1];
p = [k; s1; s2];
f = -2*x1*x1*k;
h = s1*x1/(1 + s2*x1);
