// interstage: aluminium barrel joining the stages (written by make_files.py)
lc = 0.45;
Point(1) = {0, 0, 40.2, lc};
Point(10) = {1.584826489, 0.915000000, 40.2, lc};
Point(11) = {0.915000000, 1.584826489, 40.2, lc};
Point(12) = {-0.915000000, 1.584826489, 40.2, lc};
Point(13) = {-1.584826489, 0.915000000, 40.2, lc};
Point(14) = {-1.584826489, -0.915000000, 40.2, lc};
Point(15) = {-0.915000000, -1.584826489, 40.2, lc};
Point(16) = {0.915000000, -1.584826489, 40.2, lc};
Point(17) = {1.584826489, -0.915000000, 40.2, lc};
Circle(20) = {10, 1, 11};
Circle(21) = {11, 1, 12};
Circle(22) = {12, 1, 13};
Circle(23) = {13, 1, 14};
Circle(24) = {14, 1, 15};
Circle(25) = {15, 1, 16};
Circle(26) = {16, 1, 17};
Circle(27) = {17, 1, 10};
out[] = Extrude {0, 0, 3.900000000} { Curve{20:27}; };
For i In {0:7}
  surf[i] = out[4 * i + 1];
  top[i] = out[4 * i];
EndFor
Physical Surface("interstage_wall") = {surf[]};
Physical Curve("is_low_1") = {20};
Physical Curve("is_up_1") = {top[0]};
Physical Curve("is_low_2") = {22};
Physical Curve("is_up_2") = {top[2]};
Physical Curve("is_low_3") = {24};
Physical Curve("is_up_3") = {top[4]};
Physical Curve("is_low_4") = {26};
Physical Curve("is_up_4") = {top[6]};
