% IL13-induced JAK/STAT signalling (Raia V et al., Cancer Research 71(3):693-704, 2011), as in
% STRIKE-GOLDD's models/z_create_JAKSTAT.m (also models/NLcontr_models/z_create_RaiaJAKSTAT.m and
% functions/aux_Lie_symmetry/lie_sym_models/z_create_JAKSTAT.m); written for obsan from its
% equations. Receptor Rec (x1), its internalised pool Rec_i (x2), IL13-bound receptor (x3) and its
% phosphorylated forms (x4, x5), JAK2 (x6, free pool 2.8 - x6), SHP1-dependent species (x8, pool
% 165 - x8), STAT5 pathway readouts (x10, x11, x13). The input u1 is the IL13 dose; c1 = 2.265
% and c2 = 91 are the fixed constants of the paper.
syms x1 x2 x3 x4 x5 x6 x8 x10 x11 x13
syms t1 t2 t3 t4 t5 t6 t7 t8 t9 t10 t11 t12 t13 t14 t15 t16 t17 t18 t19 t20 t21 t22
syms u1
x = [x1; x2; x3; x4; x5; x6; x8; x10; x11; x13];
p = [t1; t2; t3; t4; t5; t6; t7; t8; t9; t10; t11; t12; t13; t14; t15; t16; t17; t18; t19; t20; t21; t22];
u = u1;
c1 = 2.265;
c2 = 91;
jak_free = 2.8 - x6;
shp_free = 165 - x8;
f = [t6*x2 - t5*x1 - t1*c1*u1*x1;
     t5*x1 - t6*x2;
     t1*c1*u1*x1 - t2*jak_free*x3;
     t2*jak_free*x3 - t3*x4;
     t3*x4 - t4*x5;
     t8*c2*jak_free - t7*x6*x3/(1 + t13*x1) - t7*x6*x4/(1 + t13*x13);
     t10*c2*shp_free - t9*jak_free*x8;
     t11*shp_free;
     -t12*c1*u1*x11;
     t14*x10/(t15 + x10) - t16*x13];
h = [x1 + x3 + x4;
     t18*(x3 + x4 + x5 + 0.34 - x11);
     t19*(x4 + x5);
     t20*jak_free;
     t21*x10;
     t22*t17*x10/t11;
     x13;
     shp_free];
