% HIV dynamics (Miao, Xia, Perelson, Wu, SIAM Review 53(1):3-39, 2011), the form in
% STRIKE-GOLDD's NLcontr_models; written for obsan from its equations.
syms Tu Ti V lambda rho N delta1 c eta
x = [Tu; Ti; V];
p = [lambda; rho; N; delta1; c];
u = [eta];
f = [lambda - rho*Tu - eta*Tu*V;
     eta*Tu*V - delta1*Ti;
     N*delta1*Ti - c*V];
h = [V;
     Tu + Ti];
