% Drug-taking pharmacokinetic model, four compartments, dose as the known input, two scaled
% outputs (Merkt et al., Phys. Rev. E 92, 2015, Higher-order Lie symmetries in identifiability and
% predictability analysis of dynamic models); written for obsan from its equations.
syms x1 x2 x3 x4 k1 k2 k3 k4 k5 k6 k7 s2 s3 u1
x = [x1; x2; x3; x4];
p = [k1; k2; k3; k4; k5; k6; k7; s2; s3];
u = [u1];
f = [u1 - (k1 + k2)*x1;
     k1*x1 - (k3 + k6 + k7)*x2 + k5*x4;
     k2*x1 + k3*x2 - k4*x3;
     k6*x2 - k5*x4];
h = [s2*x2;
     s3*x3];
