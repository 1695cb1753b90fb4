syms k1 k2 k3
syms x
x = sym(char(x),[4 1]);
r1 = k1*x(1)*x(3);
xdot = sym(zeros(numel(x),1));
xdot(1) = -r1;
xdot(3) = -r1 + k2*x(4);
xdot(4) = r1 - k2*x(4) - k3*x(2)*x(4);
x0 = zeros(4,1);
x0(3) = 1.5E3;
p = [k1; k2; k3];
h = []; f = []; ics = [];
for j = 4:-1:3
    h = [h; x(j)];
end
for i = 1:2, f = [f; xdot(i + 2)]; ics = [ics, x0(i)]; end
last = i;
g = [x(last), 0].';
u = [x(1);x(2)];
x = [x(3);x(4)];
