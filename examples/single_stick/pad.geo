// launch table: steel deck 10 x 10 x 2 m (top at z = -1), four 0.6 m posts up to the hold-down
// points (written by make_files.py)
SetFactory("OpenCASCADE");
Box(1) = {-5, -5, -3, 10, 10, 2};
Box(2) = {0.994005, 0.994005, -1, 0.6, 0.6, 4.6};
Box(3) = {-1.594005, 0.994005, -1, 0.6, 0.6, 4.6};
Box(4) = {-1.594005, -1.594005, -1, 0.6, 0.6, 4.6};
Box(5) = {0.994005, -1.594005, -1, 0.6, 0.6, 4.6};
BooleanUnion(10) = { Volume{1}; Delete; }{ Volume{2:5}; Delete; };
Physical Volume("pad_steel") = {10};
Physical Surface("foundation") = Surface In BoundingBox{-5.01, -5.01, -3.01, 5.01, 5.01, -2.99};
Physical Surface("pad_post_1") = Surface In BoundingBox{0.984005, 0.984005, 3.5900000000000003, 1.604005, 1.604005, 3.61};
Physical Surface("pad_post_2") = Surface In BoundingBox{-1.604005, 0.984005, 3.5900000000000003, -0.984005, 1.604005, 3.61};
Physical Surface("pad_post_3") = Surface In BoundingBox{-1.604005, -1.604005, 3.5900000000000003, -0.984005, -0.984005, 3.61};
Physical Surface("pad_post_4") = Surface In BoundingBox{0.984005, -1.604005, 3.5900000000000003, 1.604005, -0.984005, 3.61};
