// The safety gate (DESIGN.md §3) on the paths about to be written, and the empty-print check.
#include "pipeline/gate.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>

#include <malloc.h>

#include "core/huge_pages.hpp"
#include "core/parallel.hpp"
#include "nonplanar/check.hpp"
#include "nonplanar/gcode.hpp"
#include "nonplanar/program.hpp"
#include "nonplanar/toolpaths.hpp"
#include "pipeline/gate_zones.hpp"

namespace nonplanar {

namespace {

// Paths of more points than this (8 MB of them) are trimmed from the heap once let go.
constexpr std::size_t kTrimPoints = 250000;

// Whether some layer extrudes more than the skirt.
bool prints(const std::vector<LayerToolpaths>& layers) {
  return std::any_of(layers.begin(), layers.end(), [](const LayerToolpaths& L) {
    return std::any_of(L.paths.begin(), L.paths.end(), [](const ExtrusionPath& p) {
      return p.role != ExtrusionRole::skirt && p.points.size() >= 2;
    });
  });
}

// The layers' paths go, their z and height stay (SliceJob::keep_paths false): the text holds
// them now, and the gate's search builds its grids next.
void release_paths(SliceResult& r) {
  std::size_t points = 0;
  for (LayerToolpaths& L : r.layers) {
    for (const ExtrusionPath& p : L.paths) points += p.points.size();
    std::vector<ExtrusionPath>().swap(L.paths);
  }
  r.paths_released = true;
  // Their many small blocks back to the system, else the grids take new pages beside them
  // (the bunny's peak: 171 MB untrimmed, 147 trimmed); on a small print the trim costs more
  // than it gives (3 % of the sine roof's time, 48 000 points).
  if (points > kTrimPoints) malloc_trim(0);
}

}  // namespace

// A part thinner than one extrusion, or an open sheet, slices to nothing: say so rather than
// write G-code that only draws a skirt (a lone sloped triangle once gave exit 0, a header
// claiming 274 core layers, and no extrusion).
std::optional<Error> nothing_to_print(const SliceResult& r, const TriangleMesh& mesh) {
  if (r.paths_released || prints(r.layers)) return std::nullopt;
  const BoundingBox b = bounding_box(mesh);
  char buf[240];
  std::snprintf(buf, sizeof buf,
                "nothing to print: the part (%.2f x %.2f x %.2f mm) holds no volume one "
                "extrusion can fill (smaller than a line, or an open surface)",
                b.size().x(), b.size().y(), b.size().z());
  return Error{Status::invalid_mesh, buf};
}

Expected<void> write_program(SliceResult& r, const SliceJob& job, const Context& ctx) {
  if (!r.gcode.empty()) return {};
  group_by_object(r.layers, job.objects);
  std::vector<std::string> header = r.header;
  header.insert(header.end(), job.header.begin(), job.header.end());
  auto text = make_gcode(r.layers, job.print, header, ctx);
  if (!text) return text.error();
  r.gcode = std::move(*text);
  return {};
}

namespace {

// Whether a path is another slicer's support on a plane: printed as that slicer made it, on
// layers of its own a contact distance apart (PrusaSlicer's beside a shell's core: 0.02 mm).
bool flat_support(const ExtrusionPath& p) {
  return p.role == ExtrusionRole::support &&
         std::all_of(p.points.begin(), p.points.end(),
                     [&](const Vec3& q) { return q.z() == p.points.front().z(); });
}

// Thickness within [h_min, h_max] on the paths' heights, with g's slack: the ones each
// point's extrusion was computed from (the file holds none). Not the skirt, nor supports on a
// plane (a support under a curved band is judged).
bool heights(const SliceResult& r, const LayerParams& L, const GateParams& g,
             const Violation& violation) {
  for (std::size_t li = 1; li < r.layers.size(); ++li)
    for (const ExtrusionPath& p : r.layers[li].paths) {
      if (p.role == ExtrusionRole::skirt || flat_support(p)) continue;
      for (std::size_t k = 0; k < p.points.size(); ++k)
        if ((p.height[k] < L.min_layer_height - g.thickness_slack ||
             p.height[k] > L.max_layer_height + g.thickness_slack) &&
            !violation(p.points[k], "a layer leaves the thickness limits"))
          return false;
    }
  return true;
}

// Slope within max_angle (with g's slack) on the extrusions of the program about to be
// written, read back from r.gcode: the coordinates the printer gets, not the paths they were
// rounded from. Only the print's own lines count: not the skirt, and not custom blocks (the
// user's start G-code, before any ;TYPE: or under "Custom"). Fills r.steepest_deg. `also`
// (if any) gets every move read, for a caller that wants them in the same reading.
bool slopes(SliceResult& r, const LayerParams& L, const GateParams& g, const Violation& violation,
            const std::function<void(const GcodeMove&)>& also) {
  const double tan_max = std::tan((L.max_angle_deg + g.angle_slack_deg) * M_PI / 180.0);
  double steepest = 0;
  bool go_on = true;
  for_each_gcode_move(r.gcode, [&](const GcodeMove& m) {
    if (also) also(m);
    if (!go_on || m.layer < 0 || !m.extruding() || m.type.empty() || m.type == "Custom" ||
        role_from_name(m.type) == ExtrusionRole::skirt)
      return;
    const double dxy = (m.to - m.from).head<2>().norm();
    const double dz = std::abs(m.to.z() - m.from.z());
    if (dxy <= g.slope_run) return;
    steepest = std::max(steepest, dz / dxy);
    if (dz > tan_max * dxy) go_on = violation(m.to, "an extrusion is steeper than max_angle");
  });
  r.steepest_deg = std::max(r.steepest_deg, std::atan(steepest) * 180 / M_PI);
  return go_on;
}

// Thickness where a layer's lines cross the ones under them in r.gcode (LayerGaps, as check
// measures it), among the moves `keep` accepts (null: all): where a layer is curved, the
// crossings thinner than h_min less g's slack go to `thin`, in file order (flat layers are
// the planar engine's; too thick is the paths' heights' to judge: a line over a gap by design,
// sparse infill or a bridge, crosses lines more than a layer down), among `moves`. Gives up
// when `abandon` turns true. Fills r's thickness figures (check's, to the digit).
void crossings(SliceResult& r, const LayerParams& L, const GateParams& g, const MoveReplay& moves,
               const std::atomic<bool>& abandon, std::vector<Vec3>& thin) {
  LayerGaps gaps([&](const CrossingGap& c) {
    if (c.curved && c.gap < L.min_layer_height - g.thickness_slack) thin.push_back(c.at);
    return !abandon.load(std::memory_order_relaxed);
  });
  moves([&](const PrintMove& m) {
    if (!abandon.load(std::memory_order_relaxed)) gaps.add(m);
  });
  gaps.finish();
  r.thickness_min = gaps.min, r.thickness_max = gaps.max;
}

}  // namespace

Expected<bool> gate(SliceResult& r, const SliceJob& job, const layers::BandedField* banded,
                    const Violation& violation, const Context& ctx) {
  ctx.progress("gate", 0);
  if (!heights(r, job.layers, job.gate, violation)) return false;
  if (auto w = write_program(r, job, ctx); !w) return w.error();
  ctx.progress("gate", 0);
  // Collisions and crossings only where a curved layer is within the head's reach
  // (gate_zones.hpp): on the bunny that skipped most of 24 million extrusion samples. Without
  // bands, only at the heights printed out of order (1 mm of slack for the file's rounding)
  // and up to the last layer that has such a point: the bunny's shell, 4 layers over
  // 112-128 mm of a 200 mm part, took 1.1 s searched everywhere. (Layer i of the file is
  // r.layers[i], as for the bands.) Planar layers elsewhere neither dig into earlier ones nor
  // cross them closer than their heights.
  GateZones zones = banded ? gate_zones(*banded, job.check.toolhead.reach()) : GateZones{};
  zones.find_last_layers(r.layers);
  const OutOfOrder late = banded ? OutOfOrder{} : out_of_order(r.layers);
  // A caller that wants only the text lets the paths go (a print of nothing keeps them, for
  // nothing_to_print to say so).
  if (!job.keep_paths && prints(r.layers)) release_paths(r);
  std::function<bool(const GcodeMove&)> keep;
  if (r.nonplanar)
    keep = [&](const GcodeMove& m) {
      return banded ? zones.may_matter(m, m.layer)
                    : late.may_matter(std::max(m.from.z(), m.to.z()), m.layer);
    };
  // The moves that matter, held when there are few, taken from the slopes' reading: the
  // collision search's two passes then read memory, not text, and so do the crossings when
  // the whole program is small (the gate read the sine roof's 2.4 MB five times, now twice; its
  // collision search took 40 ms reading the text twice, about 32 held). Past the most it holds
  // (GateParams::held_moves) each pass reads the text: the bunny's 690 000 would be 72 MB.
  const MoveReplay from_text = [&](const std::function<void(const PrintMove&)>& f) {
    for_each_print_move(r.gcode, keep, f);
  };
  std::vector<PrintMove> held;
  bool holding = r.nonplanar;  // until more than held_moves are kept
  const MoveReplay from_memory = [&](const std::function<void(const PrintMove&)>& f) {
    for (const PrintMove& m : held) f(m);
  };
  const std::size_t g_lines = r.nonplanar ? count_gcode_lines(r.gcode).g_lines : 0;
  const bool small = r.nonplanar && g_lines <= job.gate.held_moves;
  // The crossings on the other core while this one reads the slopes and searches for
  // collisions (on the bunny they took 0.7 s); then the file's time and filament
  // (with_print_stats' reading: 0.9 s on the bunny), kept when this program is the one
  // written (r.stats_in_gcode). Held moves are there only after the slopes' reading: the
  // file's time is measured first.
  std::atomic<bool> abandon{false};
  std::vector<Vec3> thin;
  PrintStatsStamp stamp;
  core::Background beside;
  auto cross = [&] {
    crossings(r, job.layers, job.gate, small ? from_memory : from_text, abandon, thin);
  };
  if (!small) beside.run(cross);
  if (r.nonplanar) beside.run([&] { stamp = measure_print_stats(r.gcode, job.print); });
  std::function<void(const GcodeMove&)> hold_move;
  if (holding) {
    reserve_huge(held, std::min(g_lines, job.gate.held_moves));
    hold_move = [&](const GcodeMove& m) {
      if (!holding || (keep && !keep(m))) return;
      if (held.size() < job.gate.held_moves) return held.push_back(print_move(m));
      holding = false;
      std::vector<PrintMove>().swap(held);
    };
  }
  if (!slopes(r, job.layers, job.gate, violation, hold_move)) {
    abandon = true;
    beside.wait();
    return false;
  }
  if (small) beside.run(cross);
  auto thin_ones = [&] {
    for (const Vec3& p : thin)
      if (!violation(p, "a layer crosses the one under it thinner than h_min")) return false;
    return true;
  };
  if (!r.nonplanar) {  // planar layers cannot dig into earlier ones
    beside.wait();
    return thin_ones();
  }
  // Collisions: in the program about to be written, read back as `check` reads the file, so
  // the two agree to the last digit. They are looked for even when bands already broke a
  // limit, so one retry drops every offender (each retry replans, reslices and rechecks).
  ctx.progress("collisions", 0);
  std::function<bool(const Vec3&)> looked_at;
  if (!zones.query.empty())
    looked_at = [&](const Vec3& p) {
      return std::any_of(zones.query.begin(), zones.query.end(),
                         [&](const BoundingBox& b) { return b.contains(p); });
    };
  if (!banded) looked_at = [&](const Vec3& p) { return late.looked_at(p); };
  auto figures = find_collisions(holding ? from_memory : from_text, job.check, looked_at, ctx);
  beside.wait();
  if (!figures) return figures.error();
  if (!thin_ones()) return false;
  // In place, once the search no longer reads the text (and its grids are gone): a copy of
  // the bunny's 37 MB program was alive beside them.
  stamp_print_stats(r.gcode, stamp);
  r.stats = stamp.stats, r.stats_in_gcode = true;
  r.collisions = figures->collisions;
  if (figures->collisions > 0)
    for (const Vec3& p : figures->points)
      if (!violation(p, "the nozzle would hit earlier layers")) return false;
  return true;
}

}  // namespace nonplanar
