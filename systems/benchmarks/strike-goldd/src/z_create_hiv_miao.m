% HIV dynamics (Miao, Xia, Perelson, Wu, SIAM Review 53(1):3-39, 2011), STRIKE-GOLDD's
% form with a known input; written for obsan from its equations.
syms Tu Ti V lambda rho N delta c eta
x = [Tu; Ti; V];
p = [lambda; rho; N; delta; c];
u = [eta];
f = [lambda - rho*Tu - eta*Tu*V;
     eta*Tu*V - delta*Ti;
     N*delta*Ti - c*V];
h = [V;
     Tu + Ti];
