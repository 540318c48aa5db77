// Passes over one layer of a program being mapped onto curved layers, written once for every
// route that maps G-code (another slicer's file, a shell's core and slab, a post-processed file).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "nonplanar/program.hpp"
#include "nonplanar/toolpaths.hpp"
#include "program/reach_groups.hpp"

namespace nonplanar::program {

/// Each move's path on its curved layer, by the move's index in the program (empty for travels
/// and retractions), for a window of the moves read and for every move added after them. One
/// path for each of the bunny's 656 000 moves from PrusaSlicer was about 52 MB (80 bytes
/// each), when only the 64 layers mapped at once are ever looked at.
class MovePaths {
 public:
  /// Moves from `added_from` on (the program's size when read) are the ones passes add.
  explicit MovePaths(std::size_t added_from) : added_from_(added_from) {}
  /// Holds empty paths for moves [begin, end), letting go of the window before.
  void window(std::size_t begin, std::size_t end) {
    begin_ = begin;
    std::vector<ExtrusionPath>().swap(window_);
    window_.resize(end - begin);
  }
  /// The path of a move in the window or added (anything else is a bug: out_of_range).
  ExtrusionPath& operator[](std::size_t move) {
    return move >= added_from_ ? added_.at(move - added_from_) : window_.at(move - begin_);
  }
  /// The path of the move just appended to the program.
  void push_back(ExtrusionPath p) { added_.push_back(std::move(p)); }

 private:
  std::size_t added_from_, begin_ = 0;
  std::vector<ExtrusionPath> window_, added_;
};

/// One layer at work: its lines in order, the program's moves, and each move's path on its
/// curved layer (`mapped[i]` for `moves[i]`). Passes append the moves they make (with a path,
/// or none) and rewrite `lines`.
struct LayerWork {
  std::vector<GcodeLine>& lines;
  std::vector<GcodeMove>& moves;
  MovePaths& mapped;
  /// Appends m (mapped as p) and returns the line that prints it.
  GcodeLine add(GcodeMove m, ExtrusionPath p = {});
};

/// One stroke of a top skin, as the low-to-high rule sees it: its mean height, the heights of
/// its two ends, the box round its points and its bead's width (mm).
struct StrokeHeights {
  double mean = 0, first = 0, last = 0;
  ReachBox box;
};

/// The rule of DESIGN.md §3 for one run of top-skin strokes: they print by mean height, lowest
/// first (stable), each from its low end, in groups of strokes that can touch (reach_groups.hpp),
/// a group whole before the next (by their lowest strokes). Output: the order (indices into
/// `strokes`), and for each stroke whether it is to be printed backwards.
struct LowToHigh {
  std::vector<std::size_t> order;
  std::vector<char> reverse;
};
LowToHigh low_to_high(const std::vector<StrokeHeights>& strokes, const Toolhead& head);

/// Top skins on a slope, low to high (DESIGN.md §3: a line printed beside a higher line of
/// the same layer drags the nozzle's flat through it). In each run of "Top solid infill" the
/// strokes (unbroken extrusions) are sorted by mean mapped height and each starts at its low
/// end; the travels between them are made anew, with the run's own retraction around them
/// (travels over p.skin_retract_over) and its extrusion feed rate after. The run's trailing
/// wipes become plain retractions (their path retraced the old last stroke). Needs `mapped`
/// filled.
void order_top_skins(LayerWork& layer, const LayerPassParams& p);

/// Cuts each extrusion of the layer to where margin(x, y) >= 0 (a continuous function, mm):
/// kept pieces extrude their share of E, the rest become travels, retracted around (`ret`,
/// the file's own retraction) when longer than p.clip_retract_over. Crossings are found on
/// p.clip_step steps and bisected. `samples` counts the margins looked up; past
/// p.most_clip_samples it stops and returns the line it was on (else 0). Runs before mapping:
/// `mapped` entries of new moves are empty. slope_bound(lo, hi), when given, is at least
/// |∇margin| anywhere in the box [lo, hi] (mm per mm): a move whose margin at its start is
/// farther from 0 than that slope can take it over its length is kept or cut whole without
/// its steps being looked at (the steps would all have said the same). Moves `untouched`
/// says are kept whole (another object on the plate), when it is given.
int clip_layer(LayerWork& layer, const std::function<double(double x, double y)>& margin,
               const std::function<double(const Vec2& lo, const Vec2& hi)>& slope_bound,
               const GcodeRetraction& ret, const LayerPassParams& p, std::size_t& samples,
               const std::function<bool(const GcodeMove&)>& untouched = {});

/// clip_layer in two halves, so that layers can be cut side by side and put together in
/// order: where each extrusion it cuts is cut (cut_layer; reads the layer only), then the
/// layer made of the pieces (clip_layer with the cuts). For the k-th such move of the layer
/// (in order): `steps[k]` the steps it is looked at on, `looks[k]` the margins looked up,
/// its pieces' cut parameters cuts[begin[k] … begin[k + 1]] (0 … 1) and whether each is kept
/// (kept[begin[k] − k …]). `complete`: cut_layer cut every move (not when it stopped because
/// `looked`, shared by the layers cut side by side, went past p.most_clip_samples, nor for a
/// LayerCuts it did not make).
struct LayerCuts {
  std::vector<std::uint32_t> begin{0};
  std::vector<double> cuts;
  std::vector<char> kept;
  std::vector<std::uint32_t> steps, looks;
  bool complete = false;
};
LayerCuts cut_layer(const LayerWork& layer, const std::function<double(double x, double y)>& margin,
                    const std::function<double(const Vec2& lo, const Vec2& hi)>& slope_bound,
                    const LayerPassParams& p, std::atomic<std::size_t>& looked,
                    const std::function<bool(const GcodeMove&)>& untouched = {});
/// The layer of `cuts` (cut_layer's of this layer, complete): as clip_layer, `samples` and
/// the line returned past p.most_clip_samples as it counts them.
int clip_layer(LayerWork& layer, const LayerCuts& cuts, const GcodeRetraction& ret,
               const LayerPassParams& p, std::size_t& samples,
               const std::function<bool(const GcodeMove&)>& untouched = {});

/// A layer the clip left nothing of, as steps (into `out`): only what it tells the printer
/// (M-codes: temperatures, E mode); not the fan, which follows the layers printed instead (and
/// is turned off at the end).
void dropped_layer(const std::vector<GcodeLine>& lines, ProgramLayer& out);

}  // namespace nonplanar::program
