% Logistic tumour growth N' = a N (1 - N/K), N measured (Verhulst 1838; model LOG of
% STRIKE-GOLDD's models/Cancer collection); written for obsan from its equations.
syms N a K
x = [N];
p = [a; K];
f = a*N*(1 - N/K);
h = N;
