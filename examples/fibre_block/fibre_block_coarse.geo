// A coarse mesh of the fibre block of fibre_block_fine.geo: the plain 2 x 1 x 1 box, its
// fibres not meshed, about 300 tets at the default element size 0.4 (-setnumber size 0.2: the
// middle level of the material-adapted hierarchy).
//   gmsh -3 fibre_block_coarse.geo [-setnumber size 0.2] -o fibre_block_coarse.msh
SetFactory("OpenCASCADE");
DefineConstant[ size = 0.4 ];

Box(1) = {0, 0, 0, 2, 1, 1};
Physical Volume(1) = {1};
MeshSize{ PointsOf{ Volume{1}; } } = size;
Mesh.MshFileVersion = 2.2;
