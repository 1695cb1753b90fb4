% Logistic tumour growth with a radiotherapy kill proportional to the free capacity (dose pulses
% as the known input; model RCAP of STRIKE-GOLDD's models/Cancer collection); written for obsan
% from its equations.
syms V lambda K gamma delta_ti
x = [V];
p = [lambda; K; gamma];
u = [delta_ti];
f = lambda*V*(1 - V/K) - gamma*V*(1 - V/K)*delta_ti;
h = V;
