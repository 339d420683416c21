// Control points of the four mold outlines. Drawn on a 10 mm grid, checked as rendered
// silhouettes; every outline is a simple CCW polygon once smoothed (tested).

#include "mold_outlines.h"

namespace meltlab::datasets::detail {

namespace {

constexpr bool S = true;   // sharp corner
constexpr bool N = false;  // smooth

std::vector<ControlPoint> scaled_points(std::vector<ControlPoint> p, double factor) {
  for (auto& c : p) {
    c.x_mm *= factor;
    c.y_mm *= factor;
  }
  return p;
}

// The tables are laid out one body part per line.
// clang-format off

// Side view, head to +x, hooves on y = 0. Drawn 170 x 204 mm, used at 0.9 scale.
std::vector<ControlPoint> giraffe() {
  return scaled_points(
      {
          // hind leg (far), from the hoof up its front edge
          {24, 0, S}, {37, 0, S}, {36, 8, N}, {35, 30, N}, {36, 45, N}, {37, 60, N},
          {41, 67, N},  // crotch
          // hind leg (near)
          {45, 60, N}, {46, 45, N}, {46, 30, N}, {45, 8, N}, {44, 0, S}, {57, 0, S}, {56, 8, N}, {57, 30, N},
          {58, 50, N}, {60, 66, N},
          {70, 76, N}, {79, 76, N},  // belly
          // front leg (far)
          {83, 66, N}, {84, 45, N}, {83, 30, N}, {83, 8, N}, {82, 0, S}, {95, 0, S}, {94, 8, N}, {95, 30, N},
          {96, 48, N}, {97, 60, N},
          {100, 65, N},
          // front leg (near)
          {104, 60, N}, {105, 45, N}, {104, 30, N}, {104, 8, N}, {103, 0, S}, {116, 0, S}, {115, 8, N},
          {116, 30, N}, {117, 50, N}, {118, 64, N},
          // chest and the front (lower) edge of the neck
          {122, 80, N}, {126, 96, N}, {131, 112, N}, {138, 130, N}, {145, 148, N},
          // jaw, muzzle, forehead
          {149, 158, N}, {156, 160, N}, {166, 162, N}, {172, 166, N}, {172, 173, N}, {165, 178, N}, {156, 184, N},
          // two ossicones
          {153, 187, N}, {153, 196, N}, {155, 200, N}, {151, 204, N}, {147, 200, N}, {148, 196, N}, {147, 188, N},
          {144, 189, N}, {142, 197, N}, {143, 201, N}, {138, 203, N}, {135, 199, N}, {137, 188, N},
          // ear pointing back
          {133, 186, N}, {122, 190, S}, {127, 183, N}, {131, 178, N},
          // back of the head and the mane down to the withers, back, rump
          {130, 170, N}, {124, 156, N}, {116, 140, N}, {108, 128, N}, {98, 125, N}, {80, 120, N}, {60, 116, N},
          {40, 113, N}, {28, 110, N},
          // tail with a tuft
          {20, 107, N}, {12, 100, N}, {8, 88, N}, {6, 74, N}, {3, 64, N}, {6, 56, N}, {11, 58, N}, {12, 66, N},
          {12, 76, N}, {14, 88, N}, {19, 96, N},
          // back of the thigh down to the first hoof
          {21, 92, N}, {19, 80, N}, {21, 62, N}, {24, 40, N}, {25, 20, N}, {25, 8, N},
      },
      0.9);
}

// Top view, nose to +y, symmetric about x = 0. The left half (x < 0) is drawn from the
// nose back to the tail; the right half mirrors it.
std::vector<ControlPoint> airplane() {
  const std::vector<ControlPoint> left = {
      // fuselage to the wing root
      {-7, 171, N}, {-11, 162, N}, {-12.5, 148, N}, {-13, 130, N}, {-13, 118, S},
      // leading edge with an engine nacelle sticking out ahead of it
      {-34, 103, S}, {-34, 113, N}, {-36, 119, N}, {-40, 121, N}, {-44, 119, N}, {-46, 113, N}, {-46, 95, S},
      // wing tip and trailing edge
      {-86, 67, S}, {-88, 63, N}, {-88, 47, S}, {-50, 58, N}, {-13, 73, S},
      // rear fuselage, tailplane
      {-12, 55, N}, {-10, 40, N}, {-9, 36, S}, {-40, 22, S}, {-41, 18, N}, {-41, 11, S}, {-7, 10, S}, {-4, 3, N},
  };
  std::vector<ControlPoint> p = {{0, 176, N}};  // nose
  p.insert(p.end(), left.begin(), left.end());
  p.push_back({0, -3, S});  // tail cone: the fin seen end-on
  for (auto it = left.rbegin(); it != left.rend(); ++it) p.push_back({-it->x_mm, it->y_mm, it->corner});
  return p;
}

// Side view, bow to +x, keel on y = 0.
std::vector<ControlPoint> ship() {
  return {
      // keel and raked bow
      {24, 0, S}, {136, 0, S}, {152, 5, N}, {165, 17, N}, {173, 31, N}, {178, 46, S},
      // forecastle with the foremast
      {160, 44, N}, {157, 44, S}, {157, 70, S}, {151, 70, S}, {151, 43, S},
      // deck house (two tiers, bridge forward)
      {126, 41, S}, {126, 58, S}, {120, 58, S}, {120, 74, S}, {86, 74, S}, {86, 58, S},
      // slanted funnel
      {76, 58, S}, {71, 92, S}, {53, 92, S}, {55, 58, S},
      {42, 58, S}, {42, 41, S},
      // after deck and rounded stern
      {14, 42, N}, {5, 44, S}, {6, 30, N}, {11, 14, N},
  };
}

// Side view, bow to +x, keel on y = 0: two superfiring turrets forward (A, B), two aft
// (X, Y), bridge tower with a mast, funnel.
std::vector<ControlPoint> warship() {
  return {
      // keel and pointed, raked bow
      {20, 0, S}, {150, 0, S}, {187, 36, S}, {160, 31, S},
      // turret A and its barrels
      {159, 36, S}, {177, 36, S}, {177, 41, S}, {158, 41, S}, {157, 45, S}, {143, 45, S}, {141, 38, S},
      // turret B on its barbette, firing over A
      {139, 49, S}, {158, 49, S}, {158, 54, S}, {138, 54, S}, {137, 58, S}, {122, 58, S}, {120, 45, S},
      // stepped bridge tower with a mast
      {116, 45, S}, {116, 64, S}, {112, 64, S}, {112, 80, S}, {108, 80, S}, {107.5, 93, S}, {104.5, 93, S},
      {104, 80, S}, {100, 80, S}, {100, 58, S},
      // funnel
      {92, 58, S}, {91, 78, S}, {79, 78, S}, {78, 58, S},
      // after superstructure, turret X (superfiring, barrels aft)
      {70, 58, S}, {70, 46, S}, {66, 46, S}, {65, 58, S}, {51, 58, S}, {50, 54, S}, {31, 54, S}, {31, 49, S},
      {49, 49, S}, {48, 38, S},
      // turret Y
      {46, 45, S}, {32, 45, S}, {31, 41, S}, {12, 41, S}, {12, 36, S}, {30, 36, S}, {29, 31, S},
      // quarterdeck and rounded stern
      {12, 31, N}, {3, 29, S}, {5, 15, N}, {11, 5, N},
  };
}

// clang-format on

}  // namespace

std::vector<ControlPoint> mold_control_points(Mold mold) {
  switch (mold) {
    case Mold::kGiraffe:
      return giraffe();
    case Mold::kAirplane:
      return airplane();
    case Mold::kShip:
      return ship();
    case Mold::kWarship:
      return warship();
  }
  return {};
}

}  // namespace meltlab::datasets::detail
