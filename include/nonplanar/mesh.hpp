// The triangle mesh value type shared by every stage, and the defect report of the loader.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace nonplanar {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;

/// Indexed triangle mesh in millimetres.
/// vertices: V points; faces: F triangles of vertex indices, counter-clockwise seen from
/// outside (so the right-hand normal points out of the part).
struct TriangleMesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> faces;
};

/// The objects a file places on the plate, as PrusaSlicer keeps them apart: a 3MF's build
/// items (one per object instance). STL, OBJ and OFF hold one object, and so does a 3MF of one
/// item: then both vectors are empty.
struct PlateObject {
  std::string name;
  int id = 0;    ///< PrusaSlicer's object number: the instances of one object share it
  int copy = 0;  ///< which instance of that object (0 first)
};
struct PlateObjects {
  std::vector<PlateObject> items;  ///< one per object instance, in the file's order
  std::vector<int> face;           ///< per face of the mesh: its item's index
  bool several() const { return items.size() > 1; }
};

/// Axis-aligned bounding box; empty when min > max.
struct BoundingBox {
  Vec3 min{1e300, 1e300, 1e300};
  Vec3 max{-1e300, -1e300, -1e300};
  bool empty() const { return min.x() > max.x(); }
  Vec3 size() const { return empty() ? Vec3::Zero() : Vec3(max - min); }
  void extend(const Vec3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  /// Closed box: points on its faces are inside.
  bool contains(const Vec3& p) const {
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
  }
  bool intersects(const BoundingBox& b) const {
    return (max.array() >= b.min.array()).all() && (min.array() <= b.max.array()).all();
  }
};

/// Bounding box of all vertices (including unreferenced ones).
BoundingBox bounding_box(const TriangleMesh& mesh);

/// Signed volume in mm³ (positive for a closed, outward-oriented mesh).
double signed_volume(const TriangleMesh& mesh);

/// What the loader found wrong with the input, counted on the welded mesh before repair.
struct MeshDefects {
  std::size_t open_edges = 0;          ///< edges with exactly one face
  std::size_t non_manifold_edges = 0;  ///< edges with three or more faces
  std::size_t inconsistent_edges = 0;  ///< manifold edges whose two faces disagree on winding
  std::size_t zero_area_faces = 0;     ///< faces whose height is below the weld tolerance
  std::size_t collapsed_faces = 0;     ///< faces dropped because welding merged two corners
  std::size_t duplicate_faces = 0;     ///< faces dropped as copies of another, same winding
  std::size_t shells = 0;              ///< connected components
  std::size_t faces_flipped = 0;       ///< faces whose winding the loader reversed
  bool was_inverted = false;           ///< a whole shell pointed inward and was flipped
  bool closed() const { return open_edges == 0 && non_manifold_edges == 0; }
  bool any() const {
    return open_edges || non_manifold_edges || inconsistent_edges || zero_area_faces ||
           collapsed_faces || duplicate_faces || was_inverted;
  }
};

}  // namespace nonplanar
