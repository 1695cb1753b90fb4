% Gompertz tumour growth N' = alpha N log(K/N), N measured (Gompertz 1825; model GOM2 of
% STRIKE-GOLDD's models/Cancer collection); written for obsan from its equations.
syms N alpha K
x = [N];
p = [alpha; K];
f = alpha*log(K/N)*N;
h = N;
