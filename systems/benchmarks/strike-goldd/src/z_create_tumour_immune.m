% Tumour-immune interaction with treatment rates beta1, gamma as known inputs, immune cells
% measured (model CICV of STRIKE-GOLDD's models/Cancer collection); written for obsan from its
% equations.
syms C I r1 r2 alpha1 k1 delta alpha2 alpha3 k2 beta2 beta1 gamma
x = [C; I];
p = [r1; r2; alpha1; k1; delta; alpha2; alpha3; k2; beta2];
u = [beta1; gamma];
f = [r1*C*(1 - r2*C) - alpha1*C*I/(k1 + C) - beta1*C;
     delta - alpha2*C*I + alpha3*C^2*I/(C^2 + k2) - beta2*I + gamma];
h = I;
