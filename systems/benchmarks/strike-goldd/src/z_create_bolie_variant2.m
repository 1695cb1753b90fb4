% Glucose-insulin regulation (Bolie, J. Appl. Physiol. 16(5):783-788, 1961) with numeric rates,
% as in STRIKE-GOLDD's NLcontr_models/Bolie_2: p1..p4 are declared unknown but enter no equation
% (so they are unobservable); written for obsan from its equations.
syms q1 q2 p1 p2 p3 p4 Vp delta
x = [q1; q2];
p = [p1; p2; p3; p4; Vp];
u = [delta];
f = [-q1 - 2*q2 + delta;
     -3*q2 + 4*q1];
h = q1/Vp;
