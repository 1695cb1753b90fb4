% Tumour growth V' = lambda V (1 - V/K), volume measured (model EXP2 of STRIKE-GOLDD's
% models/Cancer collection); written for obsan from its equations.
syms V lambda K
x = [V];
p = [lambda; K];
f = lambda*V*(1 - V/K);
h = V;
