% Leukaemia under immunotherapy, six states all measured, drug rate as the known input (model
% LEUK of STRIKE-GOLDD's models/Cancer collection); written for obsan from its equations.
syms T T_N E f_T h_T g_T p_T k_T p_NA p_AN p_E d_E g_MAX c_R c_F f_MIN m_K C_K e_t
x = [T; T_N; E; f_T; h_T; g_T];
p = [p_T; k_T; p_NA; p_AN; p_E; d_E; g_MAX; c_R; c_F; f_MIN; m_K; C_K];
u = [e_t];
f = [p_T*T*(1 - T/k_T) - p_NA*T + p_AN*T_N - e_t*T - f_T*h_T*E;
     -p_AN*T_N + p_NA*T;
     p_E - d_E*E - g_T*E;
     m_K*T/(C_K + T) - f_T;
     (c_F^2 + f_MIN*T^2)/(c_F^2 + T^2) - h_T;
     g_MAX*T^2/(c_R^2 + T^2) - g_T];
h = [T;
     T_N;
     E;
     f_T;
     h_T;
     g_T];
