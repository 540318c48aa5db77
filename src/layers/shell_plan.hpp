// A curved shell over a planar core: the layout for a part whose whole top is one patch that
// a stack over a plane cannot follow (DESIGN.md §2 step 4, its fallback).
//
// Notation: H(x, y) the patch's faceted top, carried over the part's whole footprint
// (faceted_top.hpp); N shell layers of thickness t, layer j (0 = lowest) spanning
// U_j − t … U_j with U_j = H − (N − 1 − j)·t; B = H − N·t the shell's bottom; z_0 = 0 < z_1 < …
// the planar core's layer boundaries; a the reach: core layer k (z_{k−1} … z_k) is printed
// only where z_k <= B + a, so the core's top under (x, y) is Z_c = max{z_k <= B + a}.
//
// Why: a stack between a plane and the top keeps one layer count under the whole patch, so a
// top that runs from the bed to 17.5 mm (the CurviSlicer wing) needs layers 17.5/N thick at
// one end and nothing at the other. Here the layer count under the top varies: the planar
// core ends in stairs under B, and the shell's lowest layer fills the stairs, so its
// thickness U_0 − Z_c lies in [t − a, t − a + h_k) for the core's layer height h_k there;
// a = t − h_min − m and h_k <= h_max − h_min − 2m keep it inside [h_min + m, h_max − m].
#pragma once

#include <algorithm>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "layers/faceted_top.hpp"
#include "layers/shell_region.hpp"
#include "nonplanar/context.hpp"
#include "nonplanar/layers.hpp"

namespace nonplanar::layers {

struct ShellPlan {
  std::vector<int> patches;  ///< the patches whose facets make the top
  FacetedTop top;            ///< H over the part's footprint
  int N = 0;
  double t = 0.2;
  double reach = 0;          ///< a, mm
  std::vector<double> core;  ///< z_0 = 0 … z_K, the core's layer boundaries, mm
  std::string refused;       ///< why the part cannot be printed this way (empty: it can)
  /// Where the shell prints (shell_region.hpp): empty when the part stands nowhere above H,
  /// else +1 on R's nodes. Outside R the core prints every layer whole.
  NodeMask region;
  /// s on H's raster, mm (shell_region.hpp); empty: the shell after the whole core.
  FacetedTop slack;
  ShellLevels levels;    ///< g (shell_levels.hpp)
  double below = 0;      ///< the bound of s⁻, min(t − a, h/2) − 0.01, mm
  bool framed = false;   ///< H covers only the patches' surroundings (plan_shell's frame)
  double banded = 0;     ///< the share of the patches printed in bands (shell_region.hpp)
  Vec2 stands_at{0, 0};  ///< where the part first stands above H (shell_region.hpp), mm
  /// What of the patches the shell leaves to the core because an overhang or another surface
  /// lies under it there, and why (empty: none).
  std::string left_out;
  /// Why the shell follows fewer patches than all those it was chosen among: the wider
  /// shell's refusal, "a shell over patches 0, 1: …" (empty: it follows them all).
  std::string narrowed;

  bool in_region(double x, double y) const { return region.empty() || region.value(x, y) >= 0; }
  /// τ (shell_region.hpp): the core's layers up to this height are printed before the shell's
  /// point (x, y, u); +inf: all of them.
  double slot_level(double x, double y, double u) const {
    if (slack.empty()) return std::numeric_limits<double>::infinity();
    const double s = slack.height(x, y);
    return std::clamp(levels.at(u), u - std::min(s, below), u + s);
  }
  double bottom(double x, double y) const { return top.height(x, y) - N * t; }
  /// The core's layer with top z is printed where H >= this level (z <= B + a), mm.
  double core_level(double z) const { return z - reach + N * t; }
  /// U_j(x, y).
  double layer_top(int j, double x, double y) const { return top.height(x, y) - (N - 1 - j) * t; }
  /// Z_c(x, y): the top of the highest core layer printed under (x, y); 0 (the bed) if none.
  double core_top(double x, double y) const;
  /// The thickness of shell layer j under (x, y): U_j minus the core's top (j = 0) or U_{j−1},
  /// never below the bed.
  double thickness(int j, double x, double y) const;
};

/// Inputs: the placed mesh, its analysis, the patches to follow together (indices into
/// a.patches) and the printer limits. Output: a plan, or one with `refused` set when the part
/// stands above most of the patches (shell_region.hpp), another printable up-facing surface or
/// an overhang lies inside the shell, or the limits leave no room for the stairs. Where some of
/// the part stands above H, the shell prints only in R, its points interleaved with the core's
/// layers by slot_level. The core's boundaries land on every flat patch's height that they can
/// reach in steps within [h_min, h_c]. `frame` > 0: H covers only the patches' box grown by
/// that much (mm), and R stops short of its edge (plan.framed).
/// `even_core`: every core layer h_c thick after the first (no landing on flat patches), so
/// the core's boundaries are planar layers PlanarLayers{z_1, h_c} that stacks can share.
/// `cancel` (if given): once set, the plan stops between its steps, refused "cancelled" (each
/// step takes up to a second or two on a large part under a sanitizer).
/// `whole_only` (if not empty): a shell the part stands above somewhere (R not everywhere) is
/// refused, with this reason, as soon as R is known (one slicer run prints a shell over the
/// whole top or not at all; the rest of the plan would be made for nothing).
ShellPlan plan_shell(const TriangleMesh& mesh, const Analysis& a, const std::vector<int>& patches,
                     const LayerParams& p, double frame = 0, bool even_core = false,
                     const Context* cancel = nullptr, std::string_view whole_only = {});

/// The shell `slice` tries when no stack can be built, or when the stacks cover less than half
/// the largest curved patch: all the patches that need curved layers as one top, or failing
/// that the group of patches near the largest (as in choose_shells), or the largest alone (refused,
/// with the first reason, when neither fits; patches empty when none needs curved layers).
/// `whole_only`: as plan_shell's (a shell the part stands above is refused, and the next
/// tried).
ShellPlan choose_shell(const TriangleMesh& mesh, const Analysis& a, const LayerParams& p,
                       std::string_view whole_only = {});

/// The shells `slice` prints together: choose_shell's first; then, when the part stands above
/// that one somewhere (its R not everywhere), one per further group of curved patches near
/// each other (boxes within 2 mm across and in height), from the largest left: the group, or
/// its largest patch alone. A further shell is kept when its patches' box lies farther than
/// the head's reach from every kept shell's patches, and it plans with R not everywhere, on
/// the same core. The bunny's back, head, ear and tail: four shells. At most `most` shells
/// (and as many groups tried); the first may be refused (nothing else then). A first shell
/// banded over more than half of its patches (p.shell_max_banded allowing it) is weighed
/// against the shells chosen as at shell_max_banded 0.5: those win when they follow at least
/// 80 % of its patches' area.
std::vector<ShellPlan> choose_shells(const TriangleMesh& mesh, const Analysis& a,
                                     const LayerParams& p, int most = 4);

/// The core's boundaries (z_0 = 0 … z_K, mm) of the shells plan_shell makes where the part
/// stands above some patch that needs curved layers (up to the part's top, landing on the flat
/// patches, the first layer chosen for H as low as those patches' lowest point), if it does: a
/// facet more than 0.1 mm over the centre of such a patch's facet, or a facet's corner more
/// than 0.1 mm over one. Else none (and none is foreseen where the part stands only beside
/// them, over H's pad: a wall round a curved floor). For a run of the core started before the
/// shells are planned: their plans say whether they print in pieces on it.
std::optional<std::vector<double>> region_shells_core(const TriangleMesh& mesh, const Analysis& a,
                                                      const LayerParams& p);

/// Which shells to choose among.
struct ShellChoice {
  int most = 4;            ///< shells at most
  std::vector<int> among;  ///< the patches to follow (empty: every one that needs curved layers)
  bool even_core = false;  ///< plan_shell's: a core whose layers stacks can share
  const Context* cancel = nullptr;  ///< plan_shell's: stop when this is cancelled
  /// plan_shell's: not empty when one slicer run prints the shell (another slicer, prepare),
  /// which then refuses one the part stands above, with this reason.
  std::string whole_only;
};
/// choose_shells over `c.among` only (the patches no stack serves, beside the stacks).
std::vector<ShellPlan> choose_shells(const TriangleMesh& mesh, const Analysis& a,
                                     const LayerParams& p, const ShellChoice& c);

/// The shells beside stacks (`stacked`: their patches): over the curved patches the stacks
/// leave, when those are 5 % of the curved area or more, on an even core, each printing only
/// where the part stands nowhere above it (a shell over the whole part would cut the stacks
/// away). `rest` gets those patches (empty: none left, or too little: no shells and no reason);
/// `why` why there are none (empty shells). The caller plans the stacks again on the core's
/// layers and checks that no shell cuts the core inside their bands.
std::vector<ShellPlan> choose_shells_beside(const TriangleMesh& mesh, const Analysis& a,
                                            const LayerParams& p, const std::vector<int>& stacked,
                                            std::vector<int>& rest, std::string& why,
                                            const Context* cancel = nullptr);

/// The shell's layer field: T = N + (z − H)/t, ζ = base + t·T, so the normalised mesh holds
/// the shell's layers as planes ζ = base + j·t … base + (j + 1)·t. Every column is curved.
/// base (mm) lifts the normalised shell: 0 for a slab on the bed (an engine's run of its
/// own), the top of the core's layers when one slicer run prints both (prepare).
class ShellField : public LayerField {
 public:
  explicit ShellField(const ShellPlan& plan, double base = 0) : s_(plan), base_(base) {}
  double T(double x, double y, double z) const override {
    return s_.N + (z - s_.top.height(x, y)) / s_.t;
  }
  double z_at(double x, double y, double t) const override {
    return s_.top.height(x, y) + (t - s_.N) * s_.t;
  }
  double zeta(double t) const override { return base_ + t * s_.t; }
  double t_of_zeta(double z) const override { return (z - base_) / s_.t; }
  double thickness(double, double, double) const override { return s_.t; }
  bool planar_at(double, double) const override { return false; }
  bool planar_along(const Vec2&, const Vec2&, double, double) const override { return false; }

 protected:
  const ShellPlan& s_;
  double base_ = 0;
};

/// ShellField for mapping the shell's toolpaths back: its lowest boundary (t = 0) is the core's
/// top Z_c instead of B, so a point on the lowest layer is as thick as what it fills
/// (ShellPlan::thickness), and so is its extrusion.
class ShellPathField final : public ShellField {
 public:
  using ShellField::ShellField;
  double z_at(double x, double y, double t) const override {
    return t < 0.5 ? std::max(s_.core_top(x, y), 0.0) : ShellField::z_at(x, y, t);
  }
};

/// The plan of a shell that prints where nothing stands above its top (region empty) as JSON
/// (docs/plan-format.md, "shell"): H's raster, N, t, the reach and the core's boundaries.
std::string shell_plan_json(const ShellPlan& plan);
/// Reads what shell_plan_json wrote, H moved by `shift` in XY (mm); every value checked.
/// Errors: parse_error saying what is wrong.
Expected<ShellPlan> parse_shell_plan_json(std::string_view text, const Vec2& shift = {0, 0});

}  // namespace nonplanar::layers
