% EGF-dependent Akt pathway (Fujita et al., Sci Signal 3(132):ra56, 2010; the benchmark
% collection's Fujita_SciSignal2010); written for obsan from its equations.
syms EGFR pEGFR pEGFR_Akt Akt pAkt S6 pAkt_S6 pS6 EGF_EGFR scaleFactor_pEGFR scaleFactor_pAkt ...
     scaleFactor_pS6 EGFR_turnover reaction_1_k1 reaction_1_k2 reaction_2_k1 reaction_2_k2 ...
     reaction_3_k1 reaction_4_k1 reaction_5_k1 reaction_5_k2 reaction_6_k1 reaction_7_k1 ...
     reaction_8_k1 reaction_9_k1 EGF_u
x = [EGFR; pEGFR; pEGFR_Akt; Akt; pAkt; S6; pAkt_S6; pS6; EGF_EGFR];
p = [scaleFactor_pEGFR; scaleFactor_pAkt; scaleFactor_pS6; EGFR_turnover; reaction_1_k1; reaction_1_k2; reaction_2_k1; reaction_2_k2; reaction_3_k1; reaction_4_k1; reaction_5_k1; reaction_5_k2; reaction_6_k1; reaction_7_k1; reaction_8_k1; reaction_9_k1];
u = [EGF_u];
f = [68190.0*EGFR_turnover - EGF_u*EGFR*reaction_1_k1 + EGF_EGFR*reaction_1_k2 - EGFR*EGFR_turnover;
     EGF_EGFR*reaction_9_k1 - pEGFR*reaction_4_k1 + pEGFR_Akt*reaction_2_k2 + pEGFR_Akt*reaction_3_k1 - Akt*pEGFR*reaction_2_k1;
     Akt*pEGFR*reaction_2_k1 - pEGFR_Akt*reaction_3_k1 - pEGFR_Akt*reaction_2_k2;
     pAkt*reaction_7_k1 + pEGFR_Akt*reaction_2_k2 - Akt*pEGFR*reaction_2_k1;
     pAkt_S6*reaction_5_k2 - pAkt*reaction_7_k1 + pAkt_S6*reaction_6_k1 + pEGFR_Akt*reaction_3_k1 - S6*pAkt*reaction_5_k1;
     pAkt_S6*reaction_5_k2 + pS6*reaction_8_k1 - S6*pAkt*reaction_5_k1;
     S6*pAkt*reaction_5_k1 - pAkt_S6*reaction_6_k1 - pAkt_S6*reaction_5_k2;
     pAkt_S6*reaction_6_k1 - pS6*reaction_8_k1;
     EGF_u*EGFR*reaction_1_k1 - EGF_EGFR*reaction_1_k2 - EGF_EGFR*reaction_9_k1];
h = [scaleFactor_pEGFR*(pEGFR + pEGFR_Akt);
     scaleFactor_pAkt*(pAkt + pAkt_S6);
     pS6*scaleFactor_pS6];
