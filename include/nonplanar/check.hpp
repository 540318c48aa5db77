// Stage check (DESIGN.md §3–4): an independent validator of a print. It reads G-code (ours or
// PrusaSlicer's / OrcaSlicer's) into moves and recomputes every quality figure from them.
#pragma once

#include <deque>
#include <functional>
#include <memory>
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

/// The figures of DESIGN.md §4. Deviation is vertical, mm; thickness is LayerGaps': the
/// height of one layer's extrusions over the previous layer's where they cross; angles in
/// degrees.
struct CheckFigures {
  std::size_t surface_samples = 0, covered_samples = 0;
  /// Samples covered and at most within_tolerance off, over all samples (an uncovered sample
  /// is not within): the share of the top printed where the mesh says. 0 without samples.
  std::size_t within_samples = 0;
  double within_share = 0;
  double deviation_mean = 0, deviation_p95 = 0, deviation_max = 0;
  double thickness_min = 0, thickness_max = 0;
  Vec3 thickness_min_at{0, 0, 0}, thickness_max_at{0, 0, 0};  ///< the crossings
  double steepest_deg = 0;
  std::size_t collisions = 0;
  Vec3 first_collision{0, 0, 0};
  int first_collision_line = 0;
  std::vector<Vec3> collision_points;  ///< where (≤ 4096, ≥ 1 mm apart), to locate them
  double volume_ratio = 0;             ///< extruded volume (skirt excluded) / mesh volume
  double outside_fraction = 0;         ///< extrusion points outside the mesh (skirt excluded)
  std::size_t extrusions = 0;
};

/// The extrusions the figures count: inside the print (after the first layer change), not the
/// skirt.
bool counted(const PrintMove& m);

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

/// One place where layer thickness was measured: where, seen from above, an extrusion crosses
/// an earlier one that is the top of the material under it there, the height of the upper
/// centre line over the lower one. at: the crossing, on the upper line. curved: a line off its
/// layer's plane takes part (planar lines over planar ones are the planar engine's: they count
/// once per layer, at the distance of the two planes).
/// spans: the two may be more than a layer apart, so it counts for the thinnest only: either
/// line is laid across gaps by design (sparse infill over its lattice, a bridge, support), or
/// the lower one was not printed in the layer just before (a shell's piece over a core).
struct CrossingGap {
  double gap = 0;
  Vec3 at{0, 0, 0};
  bool curved = false;
  bool spans = false;
};

/// Layer thickness as the file's own lines give it (DESIGN.md §3), for check and the safety
/// gate alike: wherever a layer's extrusion crosses, seen from above, an earlier layer's
/// (any of the last 24, so a shell's pieces printed between a core's layers find theirs) with
/// no other layer's bead between the two (its centre line within half its width), up to 1 mm
/// under it (deeper is a bridge). The first layer, over the bed, and the skirt do not count. Exact
/// on the chords written: a curved layer's chord that strays from its surface shows here, where a
/// thickness taken at the points would not. Moves go in file order; `visit` (may be null) sees each
/// gap and stops the measuring by returning false.
class LayerGaps {
 public:
  explicit LayerGaps(std::function<bool(const CrossingGap&)> visit = nullptr);
  ~LayerGaps();
  LayerGaps(const LayerGaps&) = delete;
  LayerGaps& operator=(const LayerGaps&) = delete;
  /// The file's next move (any kind: only the extrusions counted are kept).
  void add(const PrintMove& m);
  /// Measures the last pair of layers; then the figures are final.
  void finish();
  bool stopped() const { return stopped_; }
  double min = 0, max = 0;  ///< mm; 0 without any crossing
  Vec3 min_at{0, 0, 0}, max_at{0, 0, 0};
  std::size_t crossings = 0;

 private:
  struct Layer;
  class LineGrid;
  void close_layer();
  void measure_crossings(const Layer& up, const std::vector<Layer*>& under);
  void measure_off_plane(const Layer& up, const std::vector<Layer*>& under);
  bool cross(const Layer& up, std::size_t i, const Layer& dn, const LineGrid& g,
             const std::vector<Layer*>& under, bool first);
  static bool on_top(const Layer& dn, const std::vector<Layer*>& under, const Vec3& x, double z_dn);
  void record(const CrossingGap& g);
  std::function<bool(const CrossingGap&)> visit_;
  std::deque<std::unique_ptr<Layer>> window_;  ///< earlier layers, oldest first
  std::unique_ptr<Layer> current_;
  bool stopped_ = false;
};

/// Computes the figures; `mesh` (placed like the G-code) may be null, then deviation,
/// volume ratio and outside fraction are left at 0. Errors: cancelled.
Expected<CheckFigures> check_print(const std::vector<PrintMove>& moves, const TriangleMesh* mesh,
                                   const CheckParams& params, const Context& ctx);

}  // namespace nonplanar
