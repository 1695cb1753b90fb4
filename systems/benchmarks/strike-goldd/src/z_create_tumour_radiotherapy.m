% Exponential tumour growth with radiotherapy doses (linear-quadratic kill alpha d + beta d^2,
% dose pulses as the known input; model RAD1 of STRIKE-GOLDD's models/Cancer collection);
% written for obsan from its equations.
syms V lambda alpha beta d delta_ti
x = [V];
p = [lambda; alpha; beta; d];
u = [delta_ti];
f = lambda*V - (alpha*d + beta*d^2)*V*delta_ti;
h = V;
