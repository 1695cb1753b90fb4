syms x1 k
x = x1;
p = k;
f = -k*x1;
h = x1;
a = k;
for i = 1:60
  a = [a; a];
end
