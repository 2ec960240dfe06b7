SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {1, 0, 0, 1, 1, 1};
BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }
Physical Volume("soft", 7) = {1};
Physical Volume("hard", 3) = {2};
Physical Surface("left", 11) = {1};
Mesh.MeshSizeMin = 1.0;
Mesh.MeshSizeMax = 1.0;
