% Michaelis-Menten elimination of an infused drug: x' = u - Vm x / (Km + x), y = x / V with
% V known; written for obsan (a textbook pharmacokinetic model).
syms x V Vm Km u
x = x;
p = [Vm; Km];
u = u;
f = u - Vm*x/(Km + x);
h = x/V;
