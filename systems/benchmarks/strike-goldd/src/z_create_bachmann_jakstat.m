% JAK2/STAT5 signalling with the dual feedback of CIS and SOCS3 (Bachmann et al., Division
% of labor by dual feedback regulators controls JAK2/STAT5 signaling over broad ligand range,
% Mol Syst Biol 7:516, 2011); written for obsan from the model's equations. 25 states,
% 27 parameters (three are the initial totals init_*), 5 inputs (Epo, actinomycin D and the
% three overexpressions), 14 outputs; the SHP1 output reads the input SHP1oe.
syms EpoRJAK2 EpoRpJAK2 p1EpoRpJAK2 p2EpoRpJAK2 p12EpoRpJAK2 EpoRJAK2_CIS SHP1 SHP1Act ...
     STAT5 pSTAT5 npSTAT5 CISnRNA1 CISnRNA2 CISnRNA3 CISnRNA4 CISnRNA5 CISRNA CIS ...
     SOCS3nRNA1 SOCS3nRNA2 SOCS3nRNA3 SOCS3nRNA4 SOCS3nRNA5 SOCS3RNA SOCS3
syms CISEqc CISEqcOE CISInh CISRNADelay CISRNATurn CISTurn EpoRActJAK2 EpoRCISInh ...
     EpoRCISRemove JAK2ActEpo JAK2EpoRDeaSHP1 SHP1ActEpoR SHP1Dea SHP1ProOE SOCS3Eqc ...
     SOCS3EqcOE SOCS3Inh SOCS3RNADelay SOCS3RNATurn SOCS3Turn STAT5ActEpoR STAT5ActJAK2 ...
     STAT5Exp STAT5Imp init_EpoRJAK2 init_SHP1 init_STAT5
syms Epo ActD CISoe SOCS3oe SHP1oe
x = [EpoRJAK2; EpoRpJAK2; p1EpoRpJAK2; p2EpoRpJAK2; p12EpoRpJAK2; EpoRJAK2_CIS; SHP1; SHP1Act;
     STAT5; pSTAT5; npSTAT5; CISnRNA1; CISnRNA2; CISnRNA3; CISnRNA4; CISnRNA5; CISRNA; CIS;
     SOCS3nRNA1; SOCS3nRNA2; SOCS3nRNA3; SOCS3nRNA4; SOCS3nRNA5; SOCS3RNA; SOCS3];
p = [CISEqc; CISEqcOE; CISInh; CISRNADelay; CISRNATurn; CISTurn; EpoRActJAK2; EpoRCISInh;
     EpoRCISRemove; JAK2ActEpo; JAK2EpoRDeaSHP1; SHP1ActEpoR; SHP1Dea; SHP1ProOE; SOCS3Eqc;
     SOCS3EqcOE; SOCS3Inh; SOCS3RNADelay; SOCS3RNATurn; SOCS3Turn; STAT5ActEpoR; STAT5ActJAK2;
     STAT5Exp; STAT5Imp; init_EpoRJAK2; init_SHP1; init_STAT5];
u = [ActD; CISoe; SOCS3oe; SHP1oe; Epo];
% Compartment volumes (cytoplasm, nucleus).
vc = 0.4;
vn = 0.275;
% Inhibition of receptor activity by SOCS3, of the second phosphorylation by CIS bound to
% the receptor, and of STAT5 activation by CIS.
iS = 1 + SOCS3Inh*SOCS3/SOCS3Eqc;
iR = 1 + EpoRCISInh*EpoRJAK2_CIS;
iC = 1 + CISInh*CIS/CISEqc;
% All phosphorylated receptor, the forms phosphorylated at site 1, and the active SHP1
% dephosphorylation rate.
pAll = EpoRpJAK2 + p1EpoRpJAK2 + p2EpoRpJAK2 + p12EpoRpJAK2;
p1All = p1EpoRpJAK2 + p12EpoRpJAK2;
dephos = JAK2EpoRDeaSHP1*SHP1Act/init_SHP1;
bind = Epo*JAK2ActEpo*EpoRJAK2/iS;
site1 = EpoRActJAK2/iS;
site2 = 3*EpoRActJAK2/(iS*iR);
shp1on = SHP1ActEpoR*SHP1*pAll/init_EpoRJAK2 - SHP1Dea*SHP1Act;
stat5on = STAT5*(STAT5ActJAK2*pAll/(init_EpoRJAK2*iS) + STAT5ActEpoR*p1All^2/(init_EpoRJAK2^2*iS*iC));
transcribe = (1 - ActD)*npSTAT5/init_STAT5;
f = [dephos*pAll - bind;
     bind - (site1 + site2 + dephos)*EpoRpJAK2;
     site1*EpoRpJAK2 - (site2 + dephos)*p1EpoRpJAK2;
     site2*EpoRpJAK2 - (site1 + dephos)*p2EpoRpJAK2;
     site1*p2EpoRpJAK2 + site2*p1EpoRpJAK2 - dephos*p12EpoRpJAK2;
     -EpoRCISRemove*EpoRJAK2_CIS*p1All/init_EpoRJAK2;
     -shp1on;
     shp1on;
     STAT5Exp*npSTAT5*vn/vc - stat5on;
     stat5on - STAT5Imp*pSTAT5;
     STAT5Imp*pSTAT5*vc/vn - STAT5Exp*npSTAT5;
     CISRNATurn*transcribe - CISRNADelay*CISnRNA1;
     CISRNADelay*(CISnRNA1 - CISnRNA2);
     CISRNADelay*(CISnRNA2 - CISnRNA3);
     CISRNADelay*(CISnRNA3 - CISnRNA4);
     CISRNADelay*(CISnRNA4 - CISnRNA5);
     CISRNADelay*CISnRNA5*vn/vc - CISRNATurn*CISRNA;
     CISTurn*(CISEqc*(CISRNA + CISEqcOE*CISoe) - CIS);
     SOCS3RNATurn*transcribe - SOCS3RNADelay*SOCS3nRNA1;
     SOCS3RNADelay*(SOCS3nRNA1 - SOCS3nRNA2);
     SOCS3RNADelay*(SOCS3nRNA2 - SOCS3nRNA3);
     SOCS3RNADelay*(SOCS3nRNA3 - SOCS3nRNA4);
     SOCS3RNADelay*(SOCS3nRNA4 - SOCS3nRNA5);
     SOCS3RNADelay*SOCS3nRNA5*vn/vc - SOCS3RNATurn*SOCS3RNA;
     SOCS3Turn*(SOCS3Eqc*(SOCS3RNA + SOCS3EqcOE*SOCS3oe) - SOCS3)];
% The 14 distinct observables: total and site-1 phosphorylated receptor (two scalings),
% SOCS3 and CIS protein (absolute and relative), STAT5 total, phosphorylated and fraction,
% SHP1 (absolute, and relative to the wild type under overexpression) and the two mRNAs.
h = [2*pAll/init_EpoRJAK2;
     16*(p1EpoRpJAK2 + p2EpoRpJAK2 + p12EpoRpJAK2)/init_EpoRJAK2;
     SOCS3/SOCS3Eqc;
     (STAT5 + pSTAT5)/init_STAT5;
     pSTAT5/init_STAT5;
     STAT5;
     SHP1 + SHP1Act;
     CIS;
     SOCS3;
     100*pSTAT5/(STAT5 + pSTAT5);
     SOCS3RNA;
     CISRNA;
     (SHP1 + SHP1Act)*(1 + SHP1ProOE*SHP1oe)/init_SHP1;
     CIS/CISEqc];
