% FitzHugh-Nagumo neuron (FitzHugh 1961; Nagumo et al. 1962) with epsilon and eta known and the
% first state measured, as in STRIKE-GOLDD's observer example (its input u enters no equation);
% written for obsan from its equations.
syms x1 x2 alpha u epsilon eta
x = [x1; x2];
p = [alpha];
u = [u];
f = [-x2 + (x1 - x1^3/3);
     epsilon*alpha*x1 + -epsilon*(x2 + eta) + epsilon*alpha*x1];
h = x1;
