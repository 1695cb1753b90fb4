% CAR-T cell therapy: effector and memory CAR-T cells and tumour, tumour measured (model HCART
% of STRIKE-GOLDD's models/Cancer collection); written for obsan from its equations.
syms CT CM T phi rho epsilon theta alpha mu r b gamma
x = [CT; CM; T];
p = [phi; rho; epsilon; theta; alpha; mu; r; b; gamma];
f = [phi*CT - rho*CT + theta*T*CM - alpha*T*CT;
     epsilon*CT - theta*T*CM - mu*CM;
     r*T*(1 - b*T) - gamma*CT*T];
h = T;
