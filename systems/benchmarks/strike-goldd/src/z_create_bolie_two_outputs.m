% Glucose-insulin regulation with glucose and insulin measured (Bolie, J. Appl. Physiol.
% 16(5):783-788, 1961; STRIKE-GOLDD's variant B); written for obsan from its equations.
syms q1 q2 p1 p2 p3 p4 Vp delta
x = [q1; q2];
p = [p1; p2; p3; p4; Vp];
u = [delta];
f = [p1*q1 - p2*q2 + delta;
     p3*q2 + p4*q1];
h = [q1/Vp;
     q2/Vp];
