% Tumour cells in two cycle phases x1, x2 under a drug C(t), a resistant fraction n driven by an
% input theta(t), and a logistic tumour volume V, the volume measured (model CYCLE of
% STRIKE-GOLDD's models/Cancer collection); written for obsan from its equations. The drug and
% the switch are known functions of time, declared after the parameters as in the source, so
% the param theta (in no equation) and the input theta(t) are two symbols.
syms x1 x2 n V
x = [x1; x2; n; V];
syms AG AR a epsilon theta delta alphaG K
p = [AG; AR; a; epsilon; theta; delta; alphaG; K];
syms C(t) theta(t)
u = [C(t); theta(t)];
f = [(AG*x2 - AR*x1)*x1;
     (C(t) + (1 - C(t))*AR*x2)*x2 - (AG*x2 - AR*x1)*x2;
     epsilon*n*(1 - n)*(theta(t)*x2 + (x2 - 1));
     (delta + alphaG)*V*(1 - V/K)];
h = V;
