// Post and lintel: two piers carrying a lintel, one Physical Surface per block [m].
// The surfaces share points and lines (a conforming mesh); masonry_fdem.geometry.read_msh
// with blocks="physical" duplicates the shared nodes so the three blocks are separate.
//   from masonry_fdem.geometry import read_msh
//   blocks = read_msh("meshes/post_and_lintel.geo", materials={"pier:*": "stone",
//                                                              "lintel": "stone"})
lc = 0.1;
w = 0.3;  // pier width
h = 1.2;  // pier height
s = 0.8;  // clear span
t = 0.25; // lintel depth
Point(1) = {0, 0, 0, lc};     Point(2) = {w, 0, 0, lc};
Point(3) = {w, h, 0, lc};     Point(4) = {0, h, 0, lc};
Point(5) = {w + s, 0, 0, lc}; Point(6) = {2*w + s, 0, 0, lc};
Point(7) = {2*w + s, h, 0, lc}; Point(8) = {w + s, h, 0, lc};
Point(9) = {2*w + s, h + t, 0, lc}; Point(10) = {0, h + t, 0, lc};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Line(5) = {5, 6}; Line(6) = {6, 7}; Line(7) = {7, 8}; Line(8) = {8, 5};
Line(9) = {3, 8}; Line(10) = {7, 9}; Line(11) = {9, 10}; Line(12) = {10, 4};
Curve Loop(1) = {1, 2, 3, 4};       Plane Surface(1) = {1};
Curve Loop(2) = {5, 6, 7, 8};       Plane Surface(2) = {2};
Curve Loop(3) = {-3, 9, -7, 10, 11, 12}; Plane Surface(3) = {3};
Physical Surface("pier:left") = {1};
Physical Surface("pier:right") = {2};
Physical Surface("lintel") = {3};
