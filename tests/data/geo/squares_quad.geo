// Two quad-meshed squares side by side (materials 5 and 6), a boundary curve and a stray
// point with physical groups (skipped by coarsegrain), no renumbering (sparse node tags).
Point(1) = {0, 0, 0, 1.0};
Point(2) = {2, 0, 0, 1.0};
Point(3) = {2, 1, 0, 1.0};
Point(4) = {0, 1, 0, 1.0};
Point(5) = {1, 0, 0, 1.0};
Point(6) = {1, 1, 0, 1.0};
Point(7) = {5, 5, 0, 1.0};
Line(1) = {1, 5}; Line(2) = {5, 6}; Line(3) = {6, 4}; Line(4) = {4, 1};
Line(5) = {5, 2}; Line(6) = {2, 3}; Line(7) = {3, 6};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Curve Loop(2) = {5, 6, 7, -2}; Plane Surface(2) = {2};
Recombine Surface{1, 2};
Physical Surface(5) = {1};
Physical Surface(6) = {2};
Physical Curve(9) = {4};
Physical Point(4) = {7};
Mesh.Renumber = 0;
