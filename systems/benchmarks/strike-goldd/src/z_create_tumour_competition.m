% Competing drug-sensitive and resistant tumour cells (Lotka-Volterra competition), total volume
% measured (model L_V of STRIKE-GOLDD's models/Cancer collection); written for obsan from its
% equations.
syms V_S V_R lambda_S lambda_R K_S K_R gamma_R gamma_S
x = [V_S; V_R];
p = [lambda_S; lambda_R; K_S; K_R; gamma_R; gamma_S];
f = [lambda_S*V_S*(1 - V_S/K_S - gamma_R*(V_R/K_S));
     lambda_R*V_R*(1 - V_R/K_R - gamma_S*(V_S/K_R))];
h = V_S + V_R;
