syms x1 k
x = x1;
p = k;
f = -k*x1;
h = x1;
g = zeros(1,3); for i = 1:3, g(i) = i*k; end
