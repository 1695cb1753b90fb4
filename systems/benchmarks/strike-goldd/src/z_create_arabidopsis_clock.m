% The circadian clock of Arabidopsis thaliana (Locke J, Millar A, Turner M, J Theor Biol
% 234:383-393, 2005), as in STRIKE-GOLDD's models/z_create_Arabidopsis.m (also
% models/NLcontr_models/); written for obsan from its equations. LHY mRNA (x1), cytoplasmic and
% nuclear LHY protein (x2, x3), TOC1 mRNA (x4), cytoplasmic and nuclear TOC1 protein (x5, x6),
% light-sensitive protein P (x7). The input u1 is light; the Hill exponent a of TOC1's activation
% of LHY is unknown. The mRNAs are measured.
syms x1 x2 x3 x4 x5 x6 x7
syms a n1 n2 g1 g2 k1 k2 k3 k4 k5 k6 k7 m1 m2 m3 m4 m5 m6 m7 p1 p2 p3 q1 q2 r1 r2 r3 r4
syms u1
x = [x1; x2; x3; x4; x5; x6; x7];
p = [a; n1; n2; g1; g2; k1; k2; k3; k4; k5; k6; k7; m1; m2; m3; m4; m5; m6; m7; p1; p2; p3; q1; q2; r1; r2; r3; r4];
u = u1;
f = [n1*x6^a/(g1^a + x6^a) - m1*x1/(k1 + x1) + q1*u1*x7;
     p1*x1 - r1*x2 + r2*x3 - m2*x2/(k2 + x2);
     r1*x2 - r2*x3 - m3*x3/(k3 + x3);
     n2*g2^2/(g2^2 + x3^2) - m4*x4/(k4 + x4);
     p2*x4 - r3*x5 + r4*x6 - m5*x5/(k5 + x5);
     r3*x5 - r4*x6 - m6*x6/(k6 + x6);
     p3 - m7*x7/(k7 + x7) - (p3 + q2*x7)*u1];
h = [x1; x4];
