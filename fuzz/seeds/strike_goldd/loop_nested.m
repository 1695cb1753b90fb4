syms x1 k
x = x1;
p = k;
f = -k*x1;
h = x1;
a = [];
for i = 1:3
 for j = i:-1:1
  a = [a; x1^j + i];
 end
end
b = a(2*i - 1);
