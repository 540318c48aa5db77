// Stage check (DESIGN.md §3–4): an independent validator of a print. It reads G-code (ours or
// PrusaSlicer's / OrcaSlicer's) into moves and recomputes every quality figure from them.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "nonplanar/config.hpp"
#include "nonplanar/context.hpp"
#include "nonplanar/mesh.hpp"
#include "nonplanar/program.hpp"
#include "nonplanar/toolhead.hpp"

namespace nonplanar {

/// Printer geometry and limits used by the figures. mm, degrees.
struct CheckParams {
  double max_angle_deg = 30;
  double layer_height = 0.2;  ///< h: a collision is a penetration deeper than h / 2
  Toolhead toolhead;          ///< what may not touch earlier material (toolhead.hpp)
  double filament_diameter = 1.75;
  /// Top-surface samples per mm² of facet: a facet smaller than one sample's share gets one
  /// only as its area adds up, so a finely meshed region counts no more than a coarse one.
  double surface_samples_per_mm2 = 2;
  /// The facets the deviation samples: at least min_angle_deg and below max_angle_deg from
  /// horizontal (2: the curved top only, the flat tops left out).
  double min_angle_deg = 0;
  /// A sample is "within" when a layer covers it and its deviation is at most this, mm.
  double within_tolerance = 0.03;
};

/// The figures of DESIGN.md §4. Deviation is vertical, mm; thickness is the height of each
/// extrusion above the previous layer's extrusions there (least-squares plane within
/// 0.6 mm); angles in degrees.
struct CheckFigures {
  std::size_t surface_samples = 0, covered_samples = 0;
  /// Samples covered and at most within_tolerance off, over all samples (an uncovered sample
  /// is not within): the share of the top printed where the mesh says. 0 without samples.
  std::size_t within_samples = 0;
  double within_share = 0;
  double deviation_mean = 0, deviation_p95 = 0, deviation_max = 0;
  double thickness_min = 0, thickness_max = 0;
  Vec3 thickness_min_at{0, 0, 0}, thickness_max_at{0, 0, 0};  ///< the extrusion samples
  double steepest_deg = 0;
  std::size_t collisions = 0;
  Vec3 first_collision{0, 0, 0};
  int first_collision_line = 0;
  std::vector<Vec3> collision_points;  ///< where (≤ 4096, ≥ 1 mm apart), to locate them
  double volume_ratio = 0;             ///< extruded volume (skirt excluded) / mesh volume
  double outside_fraction = 0;         ///< extrusion points outside the mesh (skirt excluded)
  std::size_t extrusions = 0;
};

/// The check's settings for a print made with `print` (layer height, filament, toolhead) and
/// facets up to `max_angle_deg` printable: the gate and `check` build them alike.
CheckParams check_params(const PrintConfig& print, double max_angle_deg);

/// Collisions with earlier layers (DESIGN.md §3), the search check_print runs, alone: for a
/// caller that needs no other figure (the slicer's safety gate). Points are looked at only
/// where `looked_at` says (null: everywhere): a caller that knows no point elsewhere can
/// collide (two planar layers never do) saves the rest; every extrusion still counts as
/// material. Errors: invalid_argument (extrusions spanning more than 2 m), cancelled.
struct CollisionFigures {
  std::size_t collisions = 0;
  Vec3 first_collision{0, 0, 0};
  int first_collision_line = 0;
  std::vector<Vec3> points;  ///< where (≤ 4096, ≥ 1 mm apart)
  std::size_t extrusions = 0;
  double steepest_deg = 0;
};
Expected<CollisionFigures> find_collisions(const std::vector<PrintMove>& moves,
                                           const CheckParams& params,
                                           const std::function<bool(const Vec3&)>& looked_at,
                                           const Context& ctx);

/// Moves played in order, as often as asked: each call calls its argument once per move.
using MoveReplay = std::function<void(const std::function<void(const PrintMove&)>&)>;

/// The same search over moves replayed twice rather than held (the gate reads them from its
/// text each time: on the bunny a vector of them was 110 MB).
Expected<CollisionFigures> find_collisions(const MoveReplay& moves, const CheckParams& params,
                                           const std::function<bool(const Vec3&)>& looked_at,
                                           const Context& ctx);

/// Computes the figures; `mesh` (placed like the G-code) may be null, then deviation,
/// volume ratio and outside fraction are left at 0. Errors: cancelled.
Expected<CheckFigures> check_print(const std::vector<PrintMove>& moves, const TriangleMesh* mesh,
                                   const CheckParams& params, const Context& ctx);

}  // namespace nonplanar
