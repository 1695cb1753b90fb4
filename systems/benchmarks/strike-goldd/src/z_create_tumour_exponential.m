% Exponential tumour growth V' = lambda V, volume measured (a classic tumour growth law;
% model EXP1 of STRIKE-GOLDD's models/Cancer collection); written for obsan from its equations.
syms V lambda
x = [V];
p = [lambda];
f = lambda*V;
h = V;
