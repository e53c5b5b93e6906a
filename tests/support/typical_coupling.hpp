#pragma once
// The 3-axis coupling the coupling tests use: a stage coupled by a few per cent, as flexure and
// tube stages are: x->y 3 %, y->x -1 %, x->z 0.5 %, y->z 1.5 %, z->x 0.8 %, z->y -2 %
// (C(j, i) = i->j).

#include "models/axis_coupling.hpp"

namespace hystloop::testing {

inline AxisMatrix typical_coupling() {
  AxisMatrix c;
  c << 1.0, -0.01, 0.008,  //
      0.03, 1.0, -0.02,    //
      0.005, 0.015, 1.0;
  return c;
}

}  // namespace hystloop::testing
