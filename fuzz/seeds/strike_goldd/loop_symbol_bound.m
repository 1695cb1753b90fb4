syms n
syms x1 k
x = x1;
p = k;
f = -k*x1;
h = x1;
for i = 1:n
end
