% Phage cocktail model (Diaz-Seoane, Sellan, Villaverde, Structural identifiability and
% observability of microbial community models); written for obsan from its equations.
syms x1 x2 x3 x4 x5 r1 r2 m kCD kPD kND E1 beta alpha Y v q u1t u2t
x = [x1; x2; x3; x4; x5];
p = [r1; r2; m; kCD; kPD; kND; E1; beta; alpha; Y; v; q];
u = [u1t; u2t];
f = [r1*x1*(1 - (x1 + x2)/kCD)*(1 - m) - kPD*x1*Y*x3/(1 + x3) - E1*x4*x1/(1 + x1 + x2);
     r2*x2*(1 - (x1 + x2)/kCD) + r1*x1*(1 - (x1 + x2)/kCD)*m - kPD*x2*Y*x5/(1 + x5) - E1*x4*x2/(1 + x1 + x2);
     beta*x1*Y*x3/(1 + x3) - Y*x1*x3 - v*x3 + q*u1t;
     alpha*x4*(1 - x4)*((x1 + x2)/(x1 + x2 + kND));
     beta*x2*Y*x5/(1 + x5) - Y*x2*x5 - v*x5 + q*u2t];
h = x4;
