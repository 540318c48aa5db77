// Mesh repair steps of the loader: welding, orientation and placement.
#pragma once

#include <cstddef>

#include "core/mesh_topology.hpp"
#include "nonplanar/io.hpp"

namespace nonplanar::io {

/// The weld tolerance (mm) for a raw mesh: `rel` times the diagonal of the box around the
/// corners of faces with non-zero area, and at most 1e-3 of the median such edge length.
/// Unused vertices and degenerate faces do not count, so one stray point far away cannot
/// widen the tolerance (a 4 mm tolerance once collapsed 5119 of 5248 faces); the edge cap
/// keeps one small far-off triangle from doing it. 0 when no face has area.
double weld_tolerance(const TriangleMesh& raw, double rel);

/// Merge vertices closer than `tolerance` (mm) and drop faces that lose a corner to the
/// merge (their count goes to *collapsed). Unreferenced vertices are removed.
/// Exact duplicates are merged by hashing first, so only unique points meet the slower
/// tolerant grid search; O(V) expected. `tags` (one per face, or null/empty) keeps step with
/// the faces.
TriangleMesh weld(TriangleMesh mesh, double tolerance, std::size_t* collapsed,
                  std::vector<int>* tags = nullptr);

/// Removes faces that repeat another face with the same winding (an STL may hold a part twice
/// over, or one facet 96k times: every later stage pays for each copy). A face and its
/// reverse are both kept. Returns how many were removed; the vertices are left as they are.
/// `tags` (one per face, or null/empty) keeps step with the faces.
std::size_t remove_duplicate_faces(TriangleMesh& mesh, std::vector<int>* tags = nullptr);

/// Faces whose height over their longest edge is below `tolerance` (needles and caps).
std::size_t count_zero_area_faces(const TriangleMesh& mesh, double tolerance);

/// Make the winding consistent across manifold edges and point every shell outward
/// (a shell with negative volume is flipped unless it lies inside another shell's
/// bounding box, where it is a cavity). Returns the number of faces flipped; sets
/// *inverted when a whole shell was inside out.
std::size_t orient_outward(TriangleMesh& mesh, const MeshTopology& topo, bool* inverted);

/// Scale, rotate (X, then Y, then Z) and, if asked, place on the bed (DESIGN.md §4).
void transform_and_place(TriangleMesh& mesh, const LoadParams& params);

}  // namespace nonplanar::io
