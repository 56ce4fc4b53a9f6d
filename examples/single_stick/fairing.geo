// payload fairing barrel (nose cone left out) (written by make_files.py)
lc = 0.6;
Point(1) = {0, 0, 51.8, lc};
Point(10) = {2.251666050, 1.300000000, 51.8, lc};
Point(11) = {1.300000000, 2.251666050, 51.8, lc};
Point(12) = {-1.300000000, 2.251666050, 51.8, lc};
Point(13) = {-2.251666050, 1.300000000, 51.8, lc};
Point(14) = {-2.251666050, -1.300000000, 51.8, lc};
Point(15) = {-1.300000000, -2.251666050, 51.8, lc};
Point(16) = {1.300000000, -2.251666050, 51.8, lc};
Point(17) = {2.251666050, -1.300000000, 51.8, lc};
Circle(20) = {10, 1, 11};
Circle(21) = {11, 1, 12};
Circle(22) = {12, 1, 13};
Circle(23) = {13, 1, 14};
Circle(24) = {14, 1, 15};
Circle(25) = {15, 1, 16};
Circle(26) = {16, 1, 17};
Circle(27) = {17, 1, 10};
out[] = Extrude {0, 0, 13.100000000} { Curve{20:27}; };
For i In {0:7}
  surf[i] = out[4 * i + 1];
  top[i] = out[4 * i];
EndFor
Physical Surface("fairing_wall") = {surf[]};
Physical Curve("fr_1") = {20};
Physical Curve("fr_2") = {22};
Physical Curve("fr_3") = {24};
Physical Curve("fr_4") = {26};
