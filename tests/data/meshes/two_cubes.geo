SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {1, 0, 0, 1, 1, 1};
Coherence;
Physical Volume(5) = {1};
Physical Volume(7) = {2};
Mesh.MeshSizeMin = 0.5;
Mesh.MeshSizeMax = 0.5;
