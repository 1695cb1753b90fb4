% Logistic tumour growth with a necrotic compartment and treatment pulses as the known input,
% viable and necrotic volumes measured (model NECR of STRIKE-GOLDD's models/Cancer collection);
% written for obsan from its equations.
syms V_t N_t lambda K eta zeta gamma delta_ti
x = [V_t; N_t];
p = [lambda; K; eta; zeta; gamma];
u = [delta_ti];
f = [lambda*V_t*(1 - V_t/K) - eta*V_t - gamma*V_t*delta_ti;
     eta*V_t - zeta*N_t + gamma*V_t*delta_ti];
h = [V_t;
     N_t];
