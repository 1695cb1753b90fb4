% Carotenoid cleavage (beta-carotene and derivatives) in Arabidopsis (Bruno et al., J Exp Bot
% 2016), the last experiment of STRIKE-GOLDD's file: five outputs, all rate constants known (state
% observability); written for obsan from its equations.
syms beta cry zea beta10 OHbeta10 betaio OHbetaio szea kbeta kcryOH kcrybeta kzea kbeta10 ...
     kOHbeta10
x = [beta; cry; zea; beta10; OHbeta10; betaio; OHbetaio];
p = [];
f = [-szea*(kbeta*beta);
     -szea*(kcryOH*cry - kcrybeta*cry);
     -szea*kzea*zea;
     szea*(kbeta*beta + kcryOH*cry - kbeta10*beta10);
     szea*(kcrybeta*cry + kzea*zea - kOHbeta10*OHbeta10);
     szea*(kbeta*beta + kcrybeta*cry + kbeta10*beta10);
     szea*(kcryOH*cry + kzea*zea + kOHbeta10*OHbeta10)];
h = [beta;
     cry;
     zea;
     beta10;
     OHbeta10];
