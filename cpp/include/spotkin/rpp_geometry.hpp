// Geometry of a roll-pitch-pitch leg, as recognised from a URDF (or given by
// hand). Leg frame: origin at the hip-roll joint, axes parallel to the body
// frame at zero angles. With o1 = 0, o2, o3 the joint origins and f the foot,
// all at zero angles in the leg frame:
//   a = o2 - o1,  b = o3 - o2,  c = f - o3,
// joint axes s1 x, s2 y, s3 y (sign[k] = +1 or -1), theta_k = sign[k] q_k, and
//   (R1)  p = Rx(theta1) ( a + Ry(theta2) ( b + Ry(theta3) c ) )
// by the product of exponentials (any rotated joint frames drop out).
#pragma once

namespace spotkin {

struct RppGeometry {
  double a[3] = {0.0, 0.110945, 0.0};  // hip roll -> hip pitch (Spot's front left leg by default)
  double b[3] = {0.025, 0.0, -0.3205};  // hip pitch -> knee
  double c[3] = {0.0, 0.0, -0.3365};   // knee -> foot
  double sign[3] = {1.0, 1.0, 1.0};     // axis signs: s1 x, s2 y, s3 y
};

}  // namespace spotkin
