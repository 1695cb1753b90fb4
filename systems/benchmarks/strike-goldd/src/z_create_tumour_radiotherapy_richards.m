% Generalized logistic tumour growth with radiotherapy doses (linear-quadratic kill, dose pulses
% as the known input; model RAD2 of STRIKE-GOLDD's models/Cancer collection); written for obsan
% from its equations.
syms V lambda alpha beta d K theta delta_ti
x = [V];
p = [lambda; alpha; beta; d; K; theta];
u = [delta_ti];
f = lambda*V*(1 - (V/K)^theta) - (alpha*d + beta*d^2)*V*delta_ti;
h = V;
