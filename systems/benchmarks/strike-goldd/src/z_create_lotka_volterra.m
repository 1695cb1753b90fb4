% Lotka-Volterra predator-prey (Lotka 1925, Volterra 1926), prey measured;
% written for obsan from the model's equations.
syms N P a b c d
x = [N; P];
p = [a; b; c; d];
f = [a*N - b*N*P;
     c*N*P - d*P];
h = N;
