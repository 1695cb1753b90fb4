% Power-law tumour growth N' = a N^gamma, gamma unknown (model POW of STRIKE-GOLDD's
% models/Cancer collection); written for obsan from its equations.
syms N a gamma
x = [N];
p = [a; gamma];
f = a*N^gamma;
h = N;
