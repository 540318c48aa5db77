#include <Eigen/Geometry>
#include <cmath>

#include "io/repair.hpp"

namespace nonplanar::io {

void transform_and_place(TriangleMesh& mesh, const LoadParams& p) {
  constexpr double kDeg = M_PI / 180.0;
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(p.rotate_z_deg * kDeg, Vec3::UnitZ()) *
                             Eigen::AngleAxisd(p.rotate_y_deg * kDeg, Vec3::UnitY()) *
                             Eigen::AngleAxisd(p.rotate_x_deg * kDeg, Vec3::UnitX()))
                                .toRotationMatrix() *
                            p.scale;
  if (!r.isIdentity(0.0))
    for (Vec3& v : mesh.vertices) v = r * v;
  if (!p.place_on_bed) return;
  const BoundingBox box = bounding_box(mesh);
  if (box.empty()) return;
  const Vec3 shift(p.bed_center.x() - 0.5 * (box.min.x() + box.max.x()),
                   p.bed_center.y() - 0.5 * (box.min.y() + box.max.y()), -box.min.z());
  for (Vec3& v : mesh.vertices) v += shift;
}

}  // namespace nonplanar::io
