% Compositional Lotka-Volterra, three taxa, one input, relative abundance of taxon 2 measured
% (Joseph, Shenhav, Xavier, Halperin, Pe'er, PLOS Comput Biol 16(5):e1007917, 2020); written for
% obsan from its equations.
syms pi1 pi2 g1 g2 A11 A12 A13 A21 A22 A23 B11 B21 u1
x = [pi1; pi2];
p = [g1; g2; A11; A12; A13; A21; A22; A23; B11; B21];
u = [u1];
f = [pi1*(g1 + A11*pi1 + A12*pi2 + A13*(1 - pi1 - pi2) + B11*u1 - pi1*(g1 + A11*pi1 + A12*pi2 + A13*(1 - pi1 - pi2) + B11*u1) - pi2*(g2 + A21*pi1 + A22*pi2 + A23*(1 - pi1 - pi2) + B21*u1));
     pi2*(g2 + A21*pi1 + A22*pi2 + A23*(1 - pi1 - pi2) + B21*u1 - pi1*(g1 + A11*pi1 + A12*pi2 + A13*(1 - pi1 - pi2) + B11*u1) - pi2*(g2 + A21*pi1 + A22*pi2 + A23*(1 - pi1 - pi2) + B21*u1))];
h = pi2;
