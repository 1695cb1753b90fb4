% Microbial community model, five states, from STRIKE-GOLDD's NLcontr_models; written for obsan
% from its equations.
syms x1 x2 x3 x4 x5 yg ya kover kg ka n m Oa Og Gin Kg kpts D l Ka kacs yh kdeg
x = [x1; x2; x3; x4; x5];
p = [yg; ya; kover; kg; ka; n; m; Oa; Og];
u = [Gin];
f = [-(kg*(x1/(x1 + Kg))*(Oa^n/(x2^n + Oa^n)))*x3 - kpts*(x1/(x1 + Kg))*(Oa^n/(x2^n + Oa^n))*x4 + D*(Gin - x1);
     (kover*(kg*(x1/(x1 + Kg))*(Oa^n/(x2^n + Oa^n)) - l) - ka*(x2/(x2 + Ka))*(Og^m/((kg*(x1/(x1 + Kg))*(Oa^n/(x2^n + Oa^n)))^m + Og^m)))*x3 + (kover*(kpts*(x1/(x1 + Kg))*(Oa^n/(x2^n + Oa^n)) - l) - (ka*(x2/(x2 + Ka))*(Og^m/((kpts*(x1/(x1 + Kg))*(Oa^n/(x2^n + Oa^n)))^m + Og^m)) + kacs*(x2/(x2 + kacs))))*x4 - D*x2;
     (1 - yh)*(yg*(kg*(x1/(x1 + Kg))*(Oa^n/(x2^n + Oa^n))) + ya*(ka*(x2/(x2 + Ka))*(Og^m/((kg*(x1/(x1 + Kg))*(Oa^n/(x2^n + Oa^n)))^m + Og^m)) - kover*(kg*(x1/(x1 + Kg))*(Oa^n/(x2^n + Oa^n)) - l)))*x3 - kdeg*x3 - D*x3;
     (yg*(kpts*(x1/(x1 + Kg))*(Oa^n/(x2^n + Oa^n))) + ya*(ka*(x2/(x2 + Ka))*(Og^m/((kpts*(x1/(x1 + Kg))*(Oa^n/(x2^n + Oa^n)))^m + Og^m)) + kacs*(x2/(x2 + kacs)) - kover*(kpts*(x1/(x1 + Kg))*(Oa^n/(x2^n + Oa^n)) - l)))*x4 - kdeg*x4 - D*x4;
     yh*(yg*(kg*(x1/(x1 + Kg))*(Oa^n/(x2^n + Oa^n))) + ya*(ka*(x2/(x2 + Ka))*(Og^m/((kg*(x1/(x1 + Kg))*(Oa^n/(x2^n + Oa^n)))^m + Og^m)) - kover*(kg*(x1/(x1 + Kg))*(Oa^n/(x2^n + Oa^n)) - l)))*x3 - kdeg*x5 - D*x5];
h = [x1;
     x2;
     x3 + x5];
