% MAPK cascade with mixed feedback (Nguyen, Degasperi, Cotter, Kholodenko, DYVIPAC, BMC Syst
% Biol 2015); written for obsan from its equations.
syms ps1 ps2 ps3 k1 k2 k3 k4 k5 k6 s1t s2t s3t KK1 KK2 n1 n2 alpha
x = [ps1; ps2; ps3];
p = [k1; k2; k3; k4; k5; k6; s1t; s2t; s3t; KK1; KK2; n1; n2; alpha];
f = [k1*(s1t - ps1)*KK1^n1/(KK1^n1 + ps3^n1) - k2*ps1;
     k3*(s2t - ps2)*ps1*(1 + alpha*ps3^n2/(KK2^n2 + ps3^n2)) - k4*ps2;
     k5*(s3t - ps3)*ps2 - k6*ps3];
h = [ps1;
     ps2;
     ps3];
