% EGF and NGF signalling to Erk in PC12 cells (Brown, Hill, Calero, Myers, Lee, Sethna, Cerione,
% "The statistical mechanics of complex signaling networks: nerve growth factor signaling",
% Phys Biol 1:184-195, 2004); written for obsan from its equations. Species x(1)..x(28);
% the ligands EGF = x(1) and NGF = x(2) are the two known inputs, the 26 others the states;
% RasGap, RapGap, PP2A and the Raf1 phosphatase are constant at 120000 molecules.
syms krbEGF kruEGF krbNGF kruNGF kEGF KmEGF kNGF KmNGF kdSos KmdSos kSos KmSos ...
     kRasGap KmRasGap kRasToRaf1 KmRasToRaf1 kpRaf1 KmpRaf1 kpBRaf KmpBRaf ...
     kdMek KmdMek kpMekCytoplasmic KmpMekCytoplasmic kdErk KmdErk kpP90Rsk KmpP90Rsk ...
     kPI3K KmPI3K kPI3KRas KmPI3KRas kAkt KmAkt kdRaf1ByAkt KmRaf1ByAkt ...
     kC3GNGF KmC3GNGF kC3G KmC3G kRapGap KmRapGap kRap1ToBRaf KmRap1ToBRaf ...
     kdRaf1 KmdRaf1 kdBRaf KmdBRaf
p = [krbEGF; kruEGF; krbNGF; kruNGF; kEGF; KmEGF; kNGF; KmNGF; kdSos; KmdSos; kSos; KmSos;
     kRasGap; KmRasGap; kRasToRaf1; KmRasToRaf1; kpRaf1; KmpRaf1; kpBRaf; KmpBRaf;
     kdMek; KmdMek; kpMekCytoplasmic; KmpMekCytoplasmic; kdErk; KmdErk; kpP90Rsk; KmpP90Rsk;
     kPI3K; KmPI3K; kPI3KRas; KmPI3KRas; kAkt; KmAkt; kdRaf1ByAkt; KmRaf1ByAkt;
     kC3GNGF; KmC3GNGF; kC3G; KmC3G; kRapGap; KmRapGap; kRap1ToBRaf; KmRap1ToBRaf;
     kdRaf1; KmdRaf1; kdBRaf; KmdBRaf];
RasGap = 120000; RapGap = 120000; PP2A = 120000; Raf1PPtase = 120000;
% 1 EGF, 2 NGF, 3/4 EGF receptor free/bound, 5/6 NGF receptor free/bound, then inactive/active
% pairs: 7/8 Sos, 9/10 P90Rsk, 11/12 Ras, 13/14 Raf1, 15/16 B-Raf, 17/18 Mek, 19/20 Erk,
% 21/22 PI3K, 23/24 Akt, 25/26 C3G, 27/28 Rap1.
x = sym('x', [28 1]);
% The 26 reaction rates (mass action for ligand binding, Michaelis-Menten otherwise).
v = sym(zeros(26, 1));
v(1) = krbEGF*x(1)*x(3);
v(2) = kruEGF*x(4);
v(3) = krbNGF*x(2)*x(5);
v(4) = kruNGF*x(6);
v(5) = kEGF*x(4)*x(7)/(x(7) + KmEGF);
v(6) = kNGF*x(6)*x(7)/(x(7) + KmNGF);
v(7) = kdSos*x(10)*x(8)/(x(8) + KmdSos);
v(8) = kSos*x(8)*x(11)/(x(11) + KmSos);
v(9) = kRasGap*RasGap*x(12)/(x(12) + KmRasGap);
v(10) = kRasToRaf1*x(12)*x(13)/(x(13) + KmRasToRaf1);
v(11) = kpRaf1*x(14)*x(17)/(x(17) + KmpRaf1);
v(12) = kpBRaf*x(16)*x(17)/(x(17) + KmpBRaf);
v(13) = kpMekCytoplasmic*x(18)*x(19)/(x(19) + KmpMekCytoplasmic);
v(14) = kdMek*PP2A*x(18)/(x(18) + KmdMek);
v(15) = kdErk*PP2A*x(20)/(x(20) + KmdErk);
v(16) = kdRaf1*Raf1PPtase*x(14)/(x(14) + KmdRaf1);
v(17) = kpP90Rsk*x(20)*x(9)/(x(9) + KmpP90Rsk);
v(18) = kPI3K*x(4)*x(21)/(x(21) + KmPI3K);
v(19) = kPI3KRas*x(12)*x(21)/(x(21) + KmPI3KRas);
v(20) = kAkt*x(22)*x(23)/(x(23) + KmAkt);
v(21) = kdRaf1ByAkt*x(24)*x(14)/(x(14) + KmRaf1ByAkt);
v(22) = kC3GNGF*x(6)*x(25)/(x(25) + KmC3GNGF);
v(23) = kC3G*x(26)*x(27)/(x(27) + KmC3G);
v(24) = kRapGap*RapGap*x(28)/(x(28) + KmRapGap);
v(25) = kRap1ToBRaf*x(28)*x(15)/(x(15) + KmRap1ToBRaf);
v(26) = kdBRaf*Raf1PPtase*x(16)/(x(16) + KmdBRaf);
% Each species' balance (the ligands' own, dx(1) and dx(2), are not kept: they are inputs).
dx = sym(zeros(numel(x), 1));
dx(1) = v(2) - v(1);
dx(2) = v(4) - v(3);
dx(3) = v(2) - v(1);
dx(4) = v(1) - v(2);
dx(5) = v(4) - v(3);
dx(6) = v(3) - v(4);
dx(7) = v(7) - v(5) - v(6);
dx(8) = v(5) + v(6) - v(7);
dx(9) = -v(17);
dx(10) = v(17);
dx(11) = v(9) - v(8);
dx(12) = v(8) - v(9);
dx(13) = v(16) + v(21) - v(10);
dx(14) = v(10) - v(16) - v(21);
dx(15) = v(26) - v(25);
dx(16) = v(25) - v(26);
dx(17) = v(14) - v(11) - v(12);
dx(18) = v(11) + v(12) - v(14);
dx(19) = v(15) - v(13);
dx(20) = v(13) - v(15);
dx(21) = -v(18) - v(19);
dx(22) = v(18) + v(19);
dx(23) = -v(20);
dx(24) = v(20);
dx(25) = -v(22);
dx(26) = v(22);
dx(27) = v(24) - v(23);
dx(28) = v(23) - v(24);
% Active Ras, Raf1, B-Raf, Mek, Erk and Rap1 are measured.
h = [x(12), x(14), x(16), x(18), x(20), x(28)].';
% States and dynamics: species 3 to 28; the ligands become the inputs.
f = [];
states = [];
for k = 3:numel(x)
    f = [f; dx(k)];
    states = [states; x(k)];
end
u = [x(1); x(2)];
x = states;
