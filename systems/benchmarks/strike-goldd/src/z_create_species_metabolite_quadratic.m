% Quadratic species-metabolite interaction model (Diaz-Seoane, Sellan, Villaverde, Structural
% identifiability and observability of microbial community models); written for obsan from its
% equations.
syms x1 x2 x3 m1 m2 psi11 psi21 psi31 psi12 psi22 psi32 d1 d2 d3 f1 f2 das1 das2 k11 k21 k31 ...
     k12 k22 k32 phi111 phi211 phi311 phi121 phi221 phi321 phi112 phi212 phi312 phi122 phi222 ...
     phi322
x = [x1; x2; x3; m1; m2];
p = [psi11; psi21; psi31; psi12; psi22; psi32; d1; d2; d3; f1; f2; das1; das2; k11; k21; k31; k12; k22; k32; phi111; phi211; phi311; phi121; phi221; phi321; phi112; phi212; phi312; phi122; phi222; phi322];
f = [x1*(psi11*m1 + psi12*m2 - d1);
     x2*(psi21*m1 + psi22*m2 - d2);
     x3*(psi31*m1 + psi32*m2 - d3);
     f1 - das1*m1 - m1*(k11*x1 + k21*x2 + k31*x3) + phi111*x1*m1 + phi211*x2*m1 + phi311*x3*m1 + phi121*x1*m2 + phi221*x2*m2 + phi321*x3*m2;
     f2 - das2*m2 - m2*(k12*x1 + k22*x2 + k32*x3) + phi112*x1*m1 + phi212*x2*m1 + phi312*x3*m1 + phi122*x1*m2 + phi222*x2*m2 + phi322*x3*m2];
h = m2;
