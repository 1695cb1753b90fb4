% Von Bertalanffy growth N' = a N^gamma - b N, gamma unknown (von Bertalanffy 1957; model BERT
% of STRIKE-GOLDD's models/Cancer collection); written for obsan from its equations.
syms N a b gamma
x = [N];
p = [a; b; gamma];
f = a*N^gamma - b*N;
h = N;
