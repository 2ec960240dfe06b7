// The fine cheese wheel (Kharevych et al. 2009, Fig. 7): a cylinder of radius 0.4 m and height
// 0.25 m lying on its flat face (axis z, bottom face at z = 0), with 16 spherical holes of radii
// 18 to 85 mm, all in the half x < 0 and at least 10 mm inside the wheel and apart (12% of that
// half's volume). Physical volume 1 is the cheese (material id 1).
//   gmsh -3 cheese_fine.geo -setnumber factor F -o cheese_fine.msh   (F scales the mesh size)
SetFactory("OpenCASCADE");
DefineConstant[ factor = 1 ];

R = 0.4;
H = 0.25;
Cylinder(1) = {0, 0, 0, 0, 0, H, R};
// x, y, z, radius of each hole
holes[] = {
  -0.19,  0.00, 0.125, 0.085,
  -0.09,  0.22, 0.12,  0.065,
  -0.10, -0.21, 0.13,  0.065,
  -0.26,  0.20, 0.14,  0.055,
  -0.27, -0.19, 0.11,  0.055,
  -0.06,  0.05, 0.06,  0.040,
  -0.06, -0.05, 0.19,  0.040,
  -0.33,  0.01, 0.065, 0.040,
  -0.34,  0.02, 0.19,  0.030,
  -0.20,  0.13, 0.215, 0.025,
  -0.19, -0.12, 0.035, 0.022,
  -0.04,  0.34, 0.17,  0.025,
  -0.04, -0.34, 0.07,  0.025,
  -0.20,  0.30, 0.05,  0.025,
  -0.20, -0.31, 0.21,  0.020,
  -0.05,  0.16, 0.22,  0.018
};
n = #holes[] / 4;
For i In {0 : n - 1}
  Sphere(2 + i) = {holes[4 * i], holes[4 * i + 1], holes[4 * i + 2], holes[4 * i + 3]};
EndFor
BooleanDifference(100) = { Volume{1}; Delete; }{ Volume{2 : n + 1}; Delete; };
Physical Volume(1) = {100};

// Element size: 27 mm in the bulk, and about 12 elements around each hole's circumference.
Mesh.MeshSizeMax = 0.027 * factor;
Mesh.MeshSizeMin = 0.004 * factor;
Mesh.MeshSizeFromCurvature = Ceil(12 / factor);
Mesh.MshFileVersion = 2.2;
