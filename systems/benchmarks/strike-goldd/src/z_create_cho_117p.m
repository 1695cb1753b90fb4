% CHO cell central carbon metabolism: model B4 of BioPreDyn-bench (Villaverde AF, Henriques D,
% Smallbone K, Bongard S, Schmid J, Cicin-Sain D, Crombach A, Saez-Rodriguez J, Mauch K, Balsa-Canto
% E, Mendes P, Jaeger J, Banga JR, "BioPreDyn-bench: a suite of benchmark problems for dynamic
% modelling in systems biology", BMC Systems Biology 9:8, 2015, open access), as in STRIKE-GOLDD's
% models/z_create_CHO_117p.m; written for obsan from the model's equations. 34 metabolite
% concentrations x1..x34 (scaled by their reference concentrations: the divisors of f), lin-log
% kinetics r = v_ss (1 + sum of elasticity * log(concentration)) with the reference fluxes v_ss and
% 117 elasticities par1..par117 (the inhibitions' with a minus sign), one saturating rate r19 with
% Michaelis-type factors x (K + c)/(K + c x), the compartments' volume ratio 0.9/0.1 = 9 and
% rho = 141.4710605; 13 metabolites measured.
% par47 and par48 enter only as par47 - par48 (both on log(x11) in r13), par55 and par57 only as
% par57 - par55 (both on log(x27) in r14), and nowhere else: so d/dpar47 + d/dpar48 and
% d/dpar55 + d/dpar57 leave every right-hand side and output unchanged, two independent
% symmetries, and the rank is at most 151 - 2 = 149 (the library's CHO_115p fixes par48 and par57).
x = sym('x', [34 1]);
par = sym('par', [117 1]);
p = par;
u = [];
h = [x5; x4; x3; x2; x1; x29; x27; x21; x15; x13; x30; x32; x11];
rho = 141.4710605;
r6 = 2413.6562849217303*9*(1 + par9*log(x8) + par10*log(x9) - par11*log(x6) - par12*log(x7));
r7 = 603.414071180172*(1 + par13*log(x12) + par14*log(x13) - par15*log(x10) - par16*log(x11));
r8 = 40133.38664791273*9*(1 + par17*log(x15) + par18*log(x6) - par19*log(x8) - par20*log(x14) + par21*log(x16));
r9 = 74836.04665510054*9*(1 + par22*log(x16) + par23*log(x7) - par24*log(x15) - par25*log(x9));
r10 = 180754.26889005644*9*(1 + par26*log(x9) + par27*log(x19) + par28*log(x20) - par29*log(x7) - par30*log(x17) - par31*log(x18));
r11 = 164390.2745505474*(1 + par32*log(x22) + par33*log(x11) - par34*log(x21) - par35*log(x13));
r12 = 36512.902220891134*(1 + par36*log(x15) + par37*log(x7) + par38*log(x21) - par39*log(x8) - par40*log(x9) + par41*log(x32) - par42*log(x30));
r13 = 166803.93083553354*(1 + par43*log(x25) + par44*log(x26) - par45*log(x23) - par46*log(x24) + par47*log(x11) - par48*log(x11) - par49*log(x13) - par50*log(x22));
r14 = 39529.972576829896*(1 + par51*log(x28) + par52*log(x29) + par53*log(x23) - par54*log(x12) - par55*log(x27) - par56*log(x25) + par57*log(x27) - par58*log(x10));
r15 = 1810.242213701644*(1 + par59*log(x32) + par60*log(x22) + par61*log(x16) - par62*log(x15) - par63*log(x30) - par64*log(x27));
r16 = 127877.37232994902*(1 + par65*log(x21) + par66*log(x23) - par67*log(x2) - par68*log(x25));
r17 = 166200.51676427448*(1 + par69*log(x24) - par70*log(x22));
r18 = 216060.34296802033*9*(1 + par71*log(x20) + par72*log(x17) - par73*log(x18) - par74*log(x19));
r19 = 5.028450593613567*x24*(par1 + 1000)/(par1 + 1000*x24)*x25*(par2 + 1000)/(par2 + 1000*x25)*x12*(par3 + 1000)/(par3 + 1000*x12)*x33*(par4 + 1000)/(par4 + 1000*x33)*x34*(par5 + 1000)/(par5 + 1000*x34)*x29*(par6 + 1000)/(par6 + 1000*x29)*x10*(par7 + 1000)/(par7 + 1000*x10)*x13*(par8 + 3000)/(par8 + 3000*x13);
r20 = 35306.0740779408*9*(1 + par75*log(x8) + par76*log(x7) + par77*log(x19) + par78*log(x31) + par79*log(x32) - par80*log(x16) - par81*log(x9) - par82*log(x17) - par83*log(x30) - par84*log(x15));
r22 = 532531.1670427525*(1 + par85*log(x11) + par86*log(x30) - par87*log(x32) - par88*log(x13));
r23 = 38926.55850561767*(1 + par89*log(x8) + par90*log(x27) - par91*log(x28) - par92*log(x16));
r24 = 40133.38664808034*(1 + par93*log(x14) + par94*log(x12) - par95*log(x29) - par96*log(x6));
r25 = 689982.1797742102*(1 + par97*log(x13) - par98*log(x11));
r26 = 495414.85075147304*9*(1 + par99*log(x32) + par100*log(x31) + par101*log(x18) - par102*log(x30) - par103*log(x20));
r27 = 2413.6562849329107*(1 + par104*log(x27) + par105*log(x31) - par106*log(x16));
r28 = 83401.9654177705*(1 + par107*log(x1) - par108*log(x26));
r29 = 603.4140712332287*(1 + par109*log(x3) - par110*log(x33));
r30 = 603.4140712332287*(1 + par111*log(x4) - par112*log(x34));
r31 = 2413.656284931604*(1 + par113*log(x6) - par114*log(x12));
r32 = 533134.5811139438*(1 + par115*log(x18) - par116*log(x31) - par117*log(x20));
f = [  (-r28/rho)/100000;
  (r16/rho)/1;
  (-r29/rho)/1000;
  (-r30/rho)/1000;
  (r19/rho)/30;
  (9*r24 - 9*r31 + r6 - r8)/1000;
  (r10 - 18*r12 - r20 + r6 - r9)/1000;
  (9*r12 - r20 - 9*r23 - r6 + r8)/1000;
  (-r10 + 18*r12 + r20 - r6 + r9)/1000;
  (-120*r19 + r7)/1000;
  (-r11 + 1260*r19 - r22 + r25 + r7)/1000;
  (r14 - 240*r19 - r24 + r31 - r7)/1000;
  (r11 - 1260*r19 + r22 - r25 - r7)/3000;
  (-9*r24 + r8)/1000;
  (-9*r12 + 9*r15 - r8 + r9)/1000;
  (-9*r15 + r20 + 9*r23 + 9*r27 - r9)/1000;
  (2*r10 - 2*r18 + 2*r20)/100;
  (4*r10 + 6*r18 - 3*r26 - 9*r32)/100;
  (-2*r10 + 2*r18 - 2*r20)/100;
  (-4*r10 - 6*r18 + 3*r26 + 9*r32)/100;
  (r11 - r12 - r16)/1000;
  (-r11 - r15 + r17)/1000;
  (r13 - r14 - r16 + 120*r19)/1000;
  (r13 - r17 - 120*r19)/1000;
  (-r13 + r14 + r16 - 120*r19)/1000;
  (-r13/2 + r28)/1000;
  (r14 + r15 - r23 - r27)/1000;
  (-r14 + 120*r19 + r23)/1000;
  (-r14 - 120*r19 + r24)/1000;
  (9*r15 + r20 - 9*r22 + r26)/3000;
  (-r20 - r26 - 9*r27 + 9*r32)/100000;
  (-9*r15 - r20 + 9*r22 - r26)/1000;
  (-120*r19 + r29)/1000;
  (-120*r19 + r30)/1000];
