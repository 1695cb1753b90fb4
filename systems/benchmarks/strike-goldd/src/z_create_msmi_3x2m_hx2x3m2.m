% Species-metabolite interaction with Monod kinetics (Diaz-Seoane, Sellan, Villaverde,
% Structural identifiability and observability of microbial community models), 3 species
% and 2 metabolites, measuring x2, x3, m2; written for obsan from its equations by
% scripts/write_msmi_variants.py.
syms x1 x2 x3 m1 m2 v11 v21 v31 v12 v22 v32 k11 k21 k31 k12 k22 k32 d1 d2 d3 vas11 vas21 vas31 vas12 vas22 vas32 kas11 kas21 kas31 kas12 kas22 kas32 f1 f2 das1 das2 phi111 phi121 phi131 phi112 phi122 phi132 phi211 phi221 phi231 phi212 phi222 phi232
x = [x1; x2; x3; m1; m2];
p = [v11; v21; v31; v12; v22; v32; k11; k21; k31; k12; k22; k32; d1; d2; d3; vas11; vas21; vas31; vas12; vas22; vas32; kas11; kas21; kas31; kas12; kas22; kas32; f1; f2; das1; das2; phi111; phi121; phi131; phi112; phi122; phi132; phi211; phi221; phi231; phi212; phi222; phi232];
f = [x1*(v11*m1/(k11 + m1*x1) + v12*m2/(k12 + m2*x1) - d1);
     x2*(v21*m1/(k21 + m1*x2) + v22*m2/(k22 + m2*x2) - d2);
     x3*(v31*m1/(k31 + m1*x3) + v32*m2/(k32 + m2*x3) - d3);
     -m1*(vas11*x1/(kas11 + m1*x1) + vas21*x2/(kas21 + m1*x2) + vas31*x3/(kas31 + m1*x3) + das1) + f1 + phi111*x1*m1/(kas11 + x1*m1) + phi121*x2*m1/(kas21 + x2*m1) + phi131*x3*m1/(kas31 + x3*m1) + phi112*x1*m2/(kas12 + x1*m2) + phi122*x2*m2/(kas22 + x2*m2) + phi132*x3*m2/(kas32 + x3*m2);
     -m2*(vas12*x1/(kas12 + m2*x1) + vas22*x2/(kas22 + m2*x2) + vas32*x3/(kas32 + m2*x3) + das2) + f2 + phi211*x1*m1/(kas11 + x1*m1) + phi221*x2*m1/(kas21 + x2*m1) + phi231*x3*m1/(kas31 + x3*m1) + phi212*x1*m2/(kas12 + x1*m2) + phi222*x2*m2/(kas22 + x2*m2) + phi232*x3*m2/(kas32 + x3*m2)];
h = [x2; x3; m2];
