// The coarse mesh of the cheese wheel: a plain prism of N sides around the wheel of
// cheese_fine.geo (radius 0.4 m, height 0.25 m), about 200 tets at the default element size
// 0.22 m. Its polygon circumscribes the circle with a 1% margin (circumradius
// 1.01 R / cos(pi / N)), so the coarse mesh contains the whole fine mesh; the holes are not
// meshed. With -setnumber size 0.11: the middle level of the material-adapted hierarchy.
//   gmsh -3 cheese_coarse.geo [-setnumber size 0.11] -o cheese_coarse.msh
SetFactory("OpenCASCADE");

R = 0.4;
H = 0.25;
N = 12;
Rc = 1.01 * R / Cos(Pi / N);
For i In {0 : N - 1}
  Point(1 + i) = {Rc * Cos(2 * Pi * i / N), Rc * Sin(2 * Pi * i / N), 0};
EndFor
For i In {0 : N - 1}
  Line(1 + i) = {1 + i, 1 + (i + 1) % N};
EndFor
Curve Loop(1) = {1 : N};
Plane Surface(1) = {1};
Extrude {0, 0, H} { Surface{1}; }
Physical Volume(1) = {1};

DefineConstant[ size = 0.22 ];
MeshSize{ PointsOf{ Volume{1}; } } = size;
Mesh.MshFileVersion = 2.2;
