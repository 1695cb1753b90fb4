% Generalized logistic (Richards) tumour growth V' = lambda/theta V (1 - (V/K)^theta), theta
% unknown (model EXP3 of STRIKE-GOLDD's models/Cancer collection); written for obsan from its equations.
syms V lambda K theta
x = [V];
p = [lambda; K; theta];
f = lambda/theta*V*(1 - (V/K)^theta);
h = V;
