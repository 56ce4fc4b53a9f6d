// The barge scenario's cargo tank (meshes.barge.build_cargo defaults) written by hand:
// a closed thick-walled cylinder along x, two 1.6 m square patches on its bottom.
SetFactory("OpenCASCADE");
L = 40.0; R = 4.2; w = 0.3; zc = 6.0 + R; x0 = -L / 2; h = 0.8;
Cylinder(1) = {x0, 0, zc, L, 0, 0, R};
Cylinder(2) = {x0 + w, 0, zc, L - 2 * w, 0, 0, R - w};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
Box(4) = {-12 - h, -h, 6.0 - 1.0, 2 * h, 2 * h, 1.0 + w / 2};
Box(5) = {12 - h, -h, 6.0 - 1.0, 2 * h, 2 * h, 1.0 + w / 2};
BooleanFragments{ Volume{3}; Delete; }{ Volume{4, 5}; Delete; }
Recursive Delete { Volume{ Volume In BoundingBox{-100, -100, 4.9, 100, 100, 6.08} }; }
Physical Volume("cargo_wall") = Volume{:};
Physical Surface("cargo_1") = Surface In BoundingBox{-12 - h - 1e-3, -h - 1e-3, 5.9, -12 + h + 1e-3, h + 1e-3, 6.1};
Physical Surface("cargo_2") = Surface In BoundingBox{12 - h - 1e-3, -h - 1e-3, 5.9, 12 + h + 1e-3, h + 1e-3, 6.1};
