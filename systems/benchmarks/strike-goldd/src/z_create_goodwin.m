% Goodwin oscillator (Goodwin, Adv. Enzyme Regul. 3:425-438, 1965), first state measured;
% written for obsan from its equations.
syms x1 x2 x3 a b AA sigma alpha beta gamma delta
x = [x1; x2; x3];
p = [a; b; AA; sigma; alpha; beta; gamma; delta];
f = [-b*x1 + a/(AA + x3^sigma);
     alpha*x1 - beta*x2;
     gamma*x2 - delta*x3];
h = x1;
