// Stage layers (paper §5–7; DESIGN.md §2 step 4, §3): curved layer stacks under the fitted
// patches, the printability cost and its optimiser, and the layer field over the whole part.
//
// Notation: h layer height, h₁ first-layer height, [h_min, h_max] allowed thickness. A patch's
// stack has N + 1 surfaces S_0 = S_f (the fitted top) ... S_N = plane z = c; the thickness of
// layer i is t_i = S_i − S_{i+1}. The layer field T(x, y, z) is a monotone layer coordinate
// (integer on layer boundaries); ζ(T) is the planar height of boundary T (ζ = z where the
// layers are planar), so the normalised mesh is (x, y, ζ(T(x, y, z))).
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "nonplanar/analysis.hpp"
#include "nonplanar/patch_fit.hpp"
#include "nonplanar/toolhead.hpp"

namespace nonplanar {

enum class StackOptimizer { gradient_descent, lbfgs };

/// Printer limits and optimiser settings. Millimetres and degrees.
struct LayerParams {
  double layer_height = 0.2;        ///< h
  double first_layer_height = 0.2;  ///< h₁
  double min_layer_height = 0.1;    ///< h_min
  double max_layer_height = 0.3;    ///< h_max
  double max_angle_deg = 30.0;      ///< steepest layer the nozzle cone allows
  /// The head: within its reach() no point of a layer may rise more than its clearance()
  /// above the nozzle tip, and the tip's flat sets how deep the steepest layers start.
  Toolhead toolhead;
  double continuity_weight = 0.05;  ///< λ of eq. (1)
  StackOptimizer optimizer = StackOptimizer::lbfgs;
  int max_iterations = 100;
  double grid_step = 0.5;  ///< quadrature and check spacing over the footprint
  /// The stack's top lies on the patch's facets (src/layers/faceted_top.hpp) rather than on
  /// the smooth fit through their vertices.
  bool faceted_top = true;
  /// Curved layers of a shell over a planar core (0: automatic, 0.4 mm of them, at least 2).
  int shell_layers = 0;
  /// The largest share of a shell's patches it may print in bands (shell_region.hpp).
  double shell_max_banded = 1.0;
};

/// The curved layers of one patch.
struct LayerStack {
  int patch = -1;
  double c = 0;         ///< the bottom plane, a planar layer boundary
  int layers = 0;       ///< N
  double T_bottom = 0;  ///< layer coordinate of the plane c
  /// S_0 (top) … S_N (plane), same knots and weights. With LayerParams::faceted_top the
  /// printed top is the facets and the printed layers keep these surfaces' proportions
  /// between it and the plane.
  std::vector<HeightField> surfaces;
  Vec2 xy_min{0, 0}, xy_max{0, 0};  ///< the patch's footprint
  // Figures over the patch, mm and degrees (after optimisation).
  double thickness_min = 0, thickness_max = 0;
  double max_slope_deg = 0;
  double max_block_rise = 0;  ///< largest rise of a layer within the block radius
  double cost_before = 0, cost_after = 0;
  /// The cost of the optimiser's own result, kept or not (cost_after is the even
  /// interpolation's when that result broke a limit).
  double cost_optimised = 0;
  int iterations = 0;
  std::string optimizer_message;
  /// When no plane let every layer clear the nozzle tip's reach uphill within
  /// max_layer_height: about the max_layer_height that would (mm; 0: none was needed, or
  /// none would do). The stack is built anyway and the final check judges it.
  double tip_needs_max_layer_height = 0;
};

/// A patch that keeps planar layers, and why.
struct PlanarFallback {
  int patch = -1;
  std::string reason;
};

class LayerField;

/// Output of plan_layers: the stacks, the fallbacks and the field built from the stacks.
struct LayerPlan {
  std::vector<LayerStack> stacks;
  std::vector<PlanarFallback> fallbacks;
  std::shared_ptr<const LayerField> field;
};

/// Build, optimise and check a stack per patch that needs non-planar layers (fits[i] is the
/// surface of analysis.patches[patch_of_fit[i]]), then the layer field. A stack that cannot
/// meet the limits falls back to planar with a reason; never an unprintable stack.
/// Errors: invalid_argument naming the key, cancelled.
Expected<LayerPlan> plan_layers(const TriangleMesh& mesh, const Analysis& analysis,
                                const std::vector<SurfaceFit>& fits,
                                const std::vector<int>& patch_of_fit, const LayerParams& params,
                                const Context& ctx);

/// Stacks plan_layers has built, by patch, for a caller that plans the same mesh, fits and
/// parameters again with fewer patches (the pipeline's retries): a stack depends only on
/// its own patch, so it is built once. Opaque; only valid for the inputs it was filled with.
class StackCache {
 public:
  StackCache();
  ~StackCache();
  StackCache(const StackCache&) = delete;
  StackCache& operator=(const StackCache&) = delete;
  struct Impl;
  Impl& impl() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

/// The surfaces plan_layers needs, fitted for the patches that need non-planar layers, in
/// patch order (*patch_of_fit), except where the facets alone refuse the patch's stack (its
/// relief, slope, the material under or above it: build_stack's checks before the surface):
/// such a patch gets its rectangle unfitted (fit_rectangle: no control points) and its refusal
/// goes into `cache`, where plan_layers finds it (it would refuse it again without), so the
/// plan is the one all fits would give. Fitting the CurviSlicer car's roof,
/// whose stack the part's hollow refuses, took a third of its slice.
/// With LayerParams::faceted_top a patch whose stack the optimiser would leave even
/// (stays_even) keeps its least-squares fit, without the rational and nonlinear refinement
/// (`fit`'s free_weights and solver): its layers are the same but for rounding (FoilCutter's
/// fit 71 → 32 ms). Such a fit serves later plans too (other planar layers, the retries).
/// Errors: as fit_patches (fit params), cancelled.
Expected<std::vector<SurfaceFit>> fit_for_plan(const TriangleMesh& mesh, const Analysis& analysis,
                                               const FitParams& fit, const LayerParams& params,
                                               StackCache& cache, std::vector<int>* patch_of_fit,
                                               const Context& ctx);

/// plan_layers, reusing and filling `cache`.
Expected<LayerPlan> plan_layers(const TriangleMesh& mesh, const Analysis& analysis,
                                const std::vector<SurfaceFit>& fits,
                                const std::vector<int>& patch_of_fit, const LayerParams& params,
                                StackCache& cache, const Context& ctx);

/// The layer field T over the whole part: planar (ζ = z) outside the curved bands, each band
/// blended C² into the planar layers around it; strictly increasing in z.
class LayerField {
 public:
  virtual ~LayerField() = default;
  /// T(x, y, z).
  virtual double T(double x, double y, double z) const = 0;
  /// z with T(x, y, z) = t (the inverse along the vertical; |error| < 1e-9 mm).
  virtual double z_at(double x, double y, double t) const = 0;
  /// z_at for n layer coordinates t[0..n) on one vertical line, into z[0..n): a field may
  /// share the work that depends on (x, y) only.
  virtual void z_at(double x, double y, const double* t, double* z, int n) const {
    for (int i = 0; i < n; ++i) z[i] = z_at(x, y, t[i]);
  }
  /// Planar height of layer coordinate t: ζ(t).
  virtual double zeta(double t) const = 0;
  /// Inverse of zeta.
  virtual double t_of_zeta(double zeta) const = 0;
  /// Local layer thickness at (x, y, z): 1 / ∂T/∂z, mm.
  virtual double thickness(double x, double y, double z) const = 0;
  /// True where no band reaches (x, y): there T is planar at every z.
  virtual bool planar_at(double x, double y) const = 0;
  /// True when T is planar on the segment a → b (XY) for every layer coordinate in
  /// [t_lo, t_hi]; may answer false for a segment that only passes near a curved band. The
  /// default samples planar_at every 0.1 mm (and ignores t).
  virtual bool planar_along(const Vec2& a, const Vec2& b, double t_lo, double t_hi) const {
    (void)t_lo, (void)t_hi;
    const double len = (b - a).norm();
    if (!(len < 1e5)) return false;  // 100 m (or NaN): no print; "curved" is the safe answer
    const int n = 1 + static_cast<int>(len / 0.1);
    for (int i = 0; i <= n; ++i) {
      const Vec2 p = a + (b - a) * (static_cast<double>(i) / n);
      if (!planar_at(p.x(), p.y())) return false;
    }
    return true;
  }
};

/// A vertical cross-section of the part as SVG: the part's outline, every layer boundary
/// inside the material (curved ones highlighted), axes in mm. axis 'x' cuts the plane
/// x = value (the picture's horizontal axis is then y); 'y' cuts y = value. Atomic.
Expected<void> write_section_svg(const std::filesystem::path& file, const TriangleMesh& mesh,
                                 const LayerPlan& plan, char axis, double value);

/// What `slice` prints when plan_layers builds no stack but the part's whole top is curved: a
/// shell of curved layers over a planar core (src/layers/shell_plan.hpp; README), or why not.
/// With `stacked` (the stacks' patches): the shells beside them over the curved patches they
/// leave (none and no reason when those are under 5 % of the curved area); slice then plans
/// the stacks again on the core's layers and checks the two together.
struct ShellSummary {
  std::vector<int> patches;  ///< the patches the shells follow; empty: no shell
  int shells = 0;            ///< one per curved region the part stands above (choose_shells)
  int layers = 0;            ///< curved layers (the most of any shell)
  double thickness = 0;      ///< of each, mm (the thickest)
  std::size_t core_layers = 0;
  std::string refused;  ///< why not (empty when there is a shell)
  /// Why the first shell follows fewer than all the curved patches: the refusal of the wider
  /// shell tried first, "a shell over patches 0, 1: …" (empty: none tried).
  std::string narrowed;
};
ShellSummary summarize_shell(const TriangleMesh& mesh, const Analysis& a, const LayerParams& p,
                             const std::vector<int>& stacked = {});

/// A planar-only field (first layer h₁, then h).
std::shared_ptr<const LayerField> planar_field(const LayerParams& params);

}  // namespace nonplanar
