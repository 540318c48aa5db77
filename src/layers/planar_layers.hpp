// Planar layer coordinate: first layer h₁, then h. T_p(z) = z / h₁ below h₁, else
// 1 + (z − h₁) / h; ζ is its inverse, so outside curved bands ζ(T(z)) = z.
#pragma once

namespace nonplanar::layers {

struct PlanarLayers {
  double h1 = 0.2, h = 0.2;
  double T(double z) const { return z <= h1 ? z / h1 : 1.0 + (z - h1) / h; }
  double dT_dz(double z) const { return z <= h1 ? 1.0 / h1 : 1.0 / h; }
  double zeta(double t) const { return t <= 1.0 ? t * h1 : h1 + (t - 1.0) * h; }
  double t_of_zeta(double z) const { return T(z); }
};

}  // namespace nonplanar::layers
