// Kharevych et al. 2009, Fig. 4: a 4 x 1 bar with a deep, thin slice of soft material cut into it
// from below (0.06 wide, 0.8 deep, at the middle). Physical surface 1 is the bar, 2 the slice:
// they are the material ids of the scene. `factor` scales every mesh size (the CI test uses 2).
SetFactory("OpenCASCADE");
DefineConstant[ factor = 1 ];
Rectangle(1) = {0, 0, 0, 4, 1};
Rectangle(2) = {1.97, 0, 0, 0.06, 0.8};
BooleanFragments{ Surface{1}; Delete; }{ Surface{2}; Delete; }
slice() = Surface In BoundingBox{1.97 - 1e-6, -1e-6, -1, 2.03 + 1e-6, 0.8 + 1e-6, 1};
bar() = Surface{:};
bar() -= slice();
Physical Surface(1) = {bar()};
Physical Surface(2) = {slice()};
// 1/32 in the bar; 1/64 in and near the slice, so that it is four triangles across.
MeshSize{ PointsOf{ Surface{:}; } } = factor / 32;
MeshSize{ PointsOf{ Surface{slice()}; } } = factor / 64;
Mesh.Algorithm = 6;
