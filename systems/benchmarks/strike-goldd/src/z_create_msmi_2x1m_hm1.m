% Species-metabolite interaction with Monod kinetics (Diaz-Seoane, Sellan, Villaverde,
% Structural identifiability and observability of microbial community models), 2 species
% and 1 metabolite, measuring m1; written for obsan from its equations by
% scripts/write_msmi_variants.py.
syms x1 x2 m1 v11 v21 k11 k21 d1 d2 vas11 vas21 kas11 kas21 f1 das1 phi111 phi121
x = [x1; x2; m1];
p = [v11; v21; k11; k21; d1; d2; vas11; vas21; kas11; kas21; f1; das1; phi111; phi121];
f = [x1*(v11*m1/(k11 + m1*x1) - d1);
     x2*(v21*m1/(k21 + m1*x2) - d2);
     -m1*(vas11*x1/(kas11 + m1*x1) + vas21*x2/(kas21 + m1*x2) - das1) + f1 + phi111*x1*m1/(kas11 + x1*m1) + phi121*x2*m1/(kas21 + x2*m1)];
h = [m1];
