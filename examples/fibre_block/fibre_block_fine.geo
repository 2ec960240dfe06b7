// The fine fibre block (a composite of the kind of Chen et al. 2019, Table 1): a 2 x 1 x 1 block
// of a soft matrix (physical volume 1) with four stiff fibres (physical volume 2) embedded along
// x: cylinders of radius 0.1 at y, z in {0.3, 0.7}, from x = 0.15 to 1.85 (they reach neither
// end face), meshed conformally (OpenCASCADE fragments).
//   gmsh -3 fibre_block_fine.geo -setnumber factor F -o fibre_block_fine.msh   (F scales the size)
SetFactory("OpenCASCADE");
DefineConstant[ factor = 1 ];

Box(1) = {0, 0, 0, 2, 1, 1};
centres[] = {0.3, 0.3,  0.3, 0.7,  0.7, 0.3,  0.7, 0.7};  // y, z of each fibre
For i In {0 : 3}
  Cylinder(2 + i) = {0.15, centres[2 * i], centres[2 * i + 1], 1.7, 0, 0, 0.1};
EndFor
out[] = BooleanFragments{ Volume{1}; Delete; }{ Volume{2 : 5}; Delete; };
// The fragments: the four fibres keep their tags 2..5, the matrix is the remaining volume.
Physical Volume(1) = {out[#out[] - 1]};
Physical Volume(2) = {2 : 5};

Mesh.MeshSizeMax = 0.07 * factor;
Mesh.MeshSizeMin = 0.02 * factor;
Mesh.MeshSizeFromCurvature = Ceil(10 / factor);
Mesh.MshFileVersion = 2.2;
