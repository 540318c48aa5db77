// Vertical rays through a closed mesh: where a column (x, y) is inside the material.
#pragma once

#include <utility>
#include <vector>

#include "nonplanar/mesh.hpp"

namespace nonplanar {

/// Buckets the mesh's triangles on an XY grid so a vertical line meets only a few.
class ColumnCaster {
 public:
  explicit ColumnCaster(const TriangleMesh& mesh, double cell = 2.0);
  /// Heights where the vertical line at (x, y) crosses the surface, sorted.
  std::vector<double> crossings(double x, double y) const;
  /// Material intervals [z_lo, z_hi] along the line, by winding number (a face whose normal
  /// points down enters material, up leaves it), so touching or overlapping shells merge.
  std::vector<std::pair<double, double>> intervals(double x, double y) const;
  /// (height, face index) of each face the vertical line at (x, y) meets, unsorted (at an
  /// edge or vertex, every face there).
  std::vector<std::pair<double, int>> face_hits(double x, double y) const;
  /// Is (x, y, z) inside the material?
  bool inside(double x, double y, double z) const;

 private:
  const TriangleMesh& mesh_;
  Vec2 origin_;
  double cell_;
  int nx_ = 0, ny_ = 0;
  std::vector<std::vector<int>> bins_;
};

}  // namespace nonplanar
