// The layer field of DESIGN.md §2 step 4: T = T_p(z) + Σ_b β_b(x, y) δ_b(x, y, z).
//
// Notation: T_p the planar coordinate; for band b (one accepted stack), δ_b = T_b − T_p where
// T_b is the stack's own coordinate (T_bottom + N − s, s the fractional layer index between
// the stack surfaces at (x, y)); above the top S_0, δ_b fades to 0 over L_rec with a
// smoothstep; below c it is 0. β_b ∈ [0, 1] is a uniform cubic B-spline over a raster
// (C²), exactly 1 on the patch, 0 beyond the blend distance; where Σβ > 1 the β are scaled
// to sum to 1, so T stays a convex combination of increasing functions of z. With a faceted
// top H (faceted_top.hpp), S_0 = H and the layers keep the control heights' proportions.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "layers/faceted_top.hpp"
#include "layers/patch_raster.hpp"
#include "layers/planar_layers.hpp"
#include "nonplanar/layers.hpp"

namespace nonplanar::layers {

struct Band {
  HeightField top;    ///< knots, weights and (x, y) map shared by the stack
  Eigen::MatrixXd Z;  ///< (N + 1) × controls: control heights of S_0 … S_N
  double c = 0, T_bottom = 0;
  int N = 0;
  double fade = 1.0;  ///< L_rec, mm
  /// Range of the top S_0 over the patch (empty when top_lo >= top_hi: no clamp). Off the
  /// patch the fit is held only by its smoothness term and can swing; there S_0 is clamped
  /// to this range and the layers under it scaled alike, so the blend zone sees a tame stack.
  double top_lo = 0, top_hi = 0;
  FacetedTop facets;  ///< the top on the facets; empty: the top is the fit (tamed by top_lo)
  // β: cubic B-spline control values on a grid (origin = node (0, 0)).
  Vec2 blend_origin{0, 0};
  double blend_cell = 0.5;
  int blend_nx = 0, blend_ny = 0;
  std::vector<double> blend;

  /// The stack's shared rational basis at (x, y): evaluate once, then any surface cheaply.
  struct Basis {
    int i0 = 0, j0 = 0;
    double R[64];
    double raw0 = 0;  ///< S_0 as the control heights give it
    double top = 0;   ///< S_0 before taming: H with facets, else raw0
  };
  Basis basis(double x, double y) const;
  /// S_i at the basis's point (off the patch: tamed, see top_lo).
  double surface(const Basis& b, int i) const;
  /// S_i as the control heights give it (no facets, no taming).
  double raw_surface(const Basis& b, int i) const;
  /// S_0 … S_N at (x, y) into S (size N + 1).
  void heights(double x, double y, double* S) const;
  double beta(double x, double y) const;
  double delta(double x, double y, double z, const PlanarLayers& pl) const;
  /// δ at height z of the column whose basis is `b` (basis(x, y) computed once per column).
  double delta(const Basis& b, double z, const PlanarLayers& pl) const;
  /// The same from the column's surfaces as S(i) gives them (= surface(b, i); a root-find
  /// over one column keeps those it has evaluated). Defined in banded_field.cpp, used there.
  template <class Surfaces>
  double delta_from(const Surfaces& S, double z, const PlanarLayers& pl) const;
};

/// β control values from a patch raster: 1 within 3 nodes of the patch (so the B-spline is
/// exactly 1 on it), then 1 − smoothstep over `blend` mm.
void set_blend(Band& b, const PatchRaster& r, double blend);

class BandedField final : public LayerField {
 public:
  BandedField(PlanarLayers pl, std::vector<Band> bands);
  double T(double x, double y, double z) const override;
  double z_at(double x, double y, double t) const override;
  void z_at(double x, double y, const double* t, double* z, int n) const override;
  double zeta(double t) const override { return pl_.zeta(t); }
  double t_of_zeta(double z) const override { return pl_.t_of_zeta(z); }
  double thickness(double x, double y, double z) const override;
  bool planar_at(double x, double y) const override {
    for (const Band& b : bands_)
      if (b.beta(x, y) > 0) return false;
    return true;
  }
  /// False when the segment crosses a band's support box within the layers it bends.
  bool planar_along(const Vec2& a, const Vec2& b, double t_lo, double t_hi) const override;
  const std::vector<Band>& bands() const { return bands_; }
  /// The bands, moved out: the field is left with none (to build one without a band).
  std::vector<Band> take_bands() {
    reach_.clear();
    return std::move(bands_);
  }
  const PlanarLayers& planar() const { return pl_; }
  /// z_at for n layer coordinates t[0..n), increasing, on one vertical line, each within tol
  /// (mm) of the exact root: on T's pieces between the surfaces (a line, or a cubic where a
  /// band fades) where they are known, else root-found from the root below it. For a check over
  /// many columns of many layers (check_blend in plan_layers.cpp), where 1e-10 mm is not needed.
  void z_column(double x, double y, const double* t, double* z, int n, double tol) const;
  /// Where a band can bend the layers: β > 0 only inside [lo, hi] (XY), and the layers only
  /// between c and z_top (its top's highest point over that box, plus its fade), i.e. for
  /// layer coordinates in (T_bottom, t_top).
  struct Reach {
    Vec2 lo, hi;
    double z_top = 0, t_top = 0;
  };
  const std::vector<Reach>& reach() const { return reach_; }

 private:
  /// T along one vertical line: the bands' β and bases depend on (x, y) only, so a root-find
  /// or a difference quotient evaluates them once (the sum keeps T's order of terms, so the
  /// value is bit-identical to T(x, y, z)).
  class Column;
  /// lo_hint: a z where T <= t (NaN: none); tol: the bracket's width to stop at, mm.
  double z_at(const Column& col, double t, double lo_hint, double tol) const;
  /// The root of T = t in [lo, hi], where T − t is flo <= 0 and fhi >= 0 (Illinois, to tol).
  double root_in(const Column& col, double t, double lo, double hi, double flo, double fhi,
                 double tol) const;
  PlanarLayers pl_;
  std::vector<Band> bands_;
  std::vector<Reach> reach_;  ///< per band
};

}  // namespace nonplanar::layers
