#include "layers/banded_field.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

#include "core/parallel.hpp"
#include "nurbs/bspline_basis.hpp"

namespace nonplanar::layers {
namespace {

double smoothstep(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

// Uniform cubic B-spline basis at fraction t for nodes i−1 … i+2.
void cubic_weights(double t, double* w) {
  const double s = 1 - t;
  w[0] = s * s * s / 6;
  w[1] = (3 * t * t * t - 6 * t * t + 4) / 6;
  w[2] = (-3 * t * t * t + 3 * t * t + 3 * t + 1) / 6;
  w[3] = t * t * t / 6;
}

}  // namespace

Band::Basis Band::basis(double x, double y) const {
  const NurbsSurface& s = top.surface;
  const Vec2 uv = top.uv(x, y);
  const double u = std::clamp(uv.x(), 0.0, 1.0), v = std::clamp(uv.y(), 0.0, 1.0);
  const int su = nurbs::find_span(s.n_u, s.p, u, s.U), sv = nurbs::find_span(s.n_v, s.q, v, s.V);
  double Nu[8], Nv[8];
  nurbs::basis_funs(su, u, s.p, s.U, Nu);
  nurbs::basis_funs(sv, v, s.q, s.V, Nv);
  Basis b;
  b.i0 = su - s.p, b.j0 = sv - s.q;
  double W = 0;
  for (int a = 0; a <= s.p; ++a)
    for (int c2 = 0; c2 <= s.q; ++c2) {
      const double r = Nu[a] * Nv[c2] * s.w(b.i0 + a, b.j0 + c2);
      b.R[a * (s.q + 1) + c2] = r;
      W += r;
    }
  for (int k = 0; k < (s.p + 1) * (s.q + 1); ++k) b.R[k] /= W;
  b.raw0 = raw_surface(b, 0);
  b.top = facets.empty() ? b.raw0 : facets.height(x, y);
  return b;
}

double Band::raw_surface(const Basis& b, int i) const {
  const NurbsSurface& s = top.surface;
  double z = 0;
  for (int a = 0; a <= s.p; ++a) {
    const int row = (b.i0 + a) * s.n_v + b.j0;
    for (int c2 = 0; c2 <= s.q; ++c2) z += b.R[a * (s.q + 1) + c2] * Z(i, row + c2);
  }
  return z;
}

double Band::surface(const Basis& b, int i) const {
  const double z = raw_surface(b, i);
  if (i == N) return z;
  if (!facets.empty()) {
    // S_0 = H; the layers under it keep the control heights' proportions. Where the fit fell
    // to the plane (off the patch) there are no proportions left: split evenly.
    if (b.raw0 - c < 0.5 * (b.top - c)) return c + (b.top - c) * (N - i) / N;
    return c + (z - c) * (b.top - c) / (b.raw0 - c);
  }
  if (top_lo >= top_hi) return z;
  const double z0 = b.top;
  if (z0 >= top_lo && z0 <= top_hi) return z;
  // Off the patch the top swings out of its range: clamp it, and scale the stack under it
  // so its layers keep their proportions (they stay ordered and between h_min and h_max as
  // on the patch). A top that fell to the plane leaves no proportions: split evenly.
  const double t0 = std::clamp(z0, top_lo, top_hi);
  if (z0 - c < 0.5 * (top_lo - c)) return c + (t0 - c) * (N - i) / N;
  return c + (z - c) * (t0 - c) / (z0 - c);
}

void Band::heights(double x, double y, double* S) const {
  const Basis b = basis(x, y);
  for (int i = 0; i <= N; ++i) S[i] = surface(b, i);
}

double Band::beta(double x, double y) const {
  const double fx = (x - blend_origin.x()) / blend_cell, fy = (y - blend_origin.y()) / blend_cell;
  const int i = static_cast<int>(std::floor(fx)), j = static_cast<int>(std::floor(fy));
  if (i < -2 || j < -2 || i > blend_nx || j > blend_ny) return 0.0;
  double wx[4], wy[4];
  cubic_weights(fx - i, wx);
  cubic_weights(fy - j, wy);
  double b = 0;
  for (int a = 0; a < 4; ++a) {
    const int ii = i - 1 + a;
    if (ii < 0 || ii >= blend_nx) continue;
    for (int c2 = 0; c2 < 4; ++c2) {
      const int jj = j - 1 + c2;
      if (jj < 0 || jj >= blend_ny) continue;
      b += wx[a] * wy[c2] * blend[static_cast<std::size_t>(ii) * blend_ny + jj];
    }
  }
  return b;
}

double Band::delta(double x, double y, double z, const PlanarLayers& pl) const {
  if (z <= c) return 0.0;
  return delta(basis(x, y), z, pl);
}

double Band::delta(const Basis& b, double z, const PlanarLayers& pl) const {
  return delta_from([&](int i) { return surface(b, i); }, z, pl);
}

template <class Surfaces>
double Band::delta_from(const Surfaces& S, double z, const PlanarLayers& pl) const {
  if (z <= c) return 0.0;
  const double S0 = S(0);
  if (z <= S0) {
    // S decreases with i: binary search for S_i ≥ z ≥ S_{i+1}.
    int lo = 0, hi = N;  // S_lo ≥ z, S_hi = c < z
    double Slo = S0, Shi = S(N);
    while (hi - lo > 1) {
      const int mid = (lo + hi) / 2;
      const double Sm = S(mid);
      if (Sm >= z)
        lo = mid, Slo = Sm;
      else
        hi = mid, Shi = Sm;
    }
    const double gap = Slo - Shi;
    const double s = lo + (gap > 0 ? std::clamp((Slo - z) / gap, 0.0, 1.0) : 0.0);
    return (T_bottom + N - s) - pl.T(z);
  }
  const double d0 = (T_bottom + N) - pl.T(S0);
  return d0 * (1.0 - smoothstep((z - S0) / fade));
}

void set_blend(Band& b, const PatchRaster& r, double blend) {
  b.blend_origin = r.origin;
  b.blend_cell = r.cell;
  b.blend_nx = r.nx;
  b.blend_ny = r.ny;
  b.blend.resize(r.dist.size());
  const double inner = 3.0 * r.cell;
  for (std::size_t k = 0; k < r.dist.size(); ++k)
    b.blend[k] = 1.0 - smoothstep((r.dist[k] - inner) / blend);
}

BandedField::BandedField(PlanarLayers pl, std::vector<Band> bands)
    : pl_(pl), bands_(std::move(bands)) {
  for (const Band& b : bands_) {
    Reach r;
    // β vanishes two cells past its raster (the support of the cubic B-spline).
    const double cell = b.blend_cell;
    r.lo = b.blend_origin - Vec2(2 * cell, 2 * cell);
    r.hi = b.blend_origin + Vec2((b.blend_nx + 1) * cell, (b.blend_ny + 1) * cell);
    // The top's highest point, sampled at the raster's nodes (a row each, side by side);
    // between them a smooth surface rises by far less than the millimetre of slack.
    std::vector<double> row_top(static_cast<std::size_t>(b.blend_nx + 4), b.c);
    core::parallel_for(0, b.blend_nx + 4, [&](int i) {
      for (int j = 0; j <= b.blend_ny + 3; ++j)
        row_top[i] =
            std::max(row_top[i], b.surface(b.basis(r.lo.x() + i * cell, r.lo.y() + j * cell), 0));
    });
    const double top = *std::max_element(row_top.begin(), row_top.end());
    r.z_top = top + b.fade + 1.0;
    r.t_top = pl_.T(r.z_top);
    reach_.push_back(r);
  }
}

bool BandedField::planar_along(const Vec2& a, const Vec2& b, double t_lo, double t_hi) const {
  for (std::size_t n = 0; n < reach_.size(); ++n) {
    const Reach& r = reach_[n];
    if (t_hi <= bands_[n].T_bottom || t_lo >= r.t_top) continue;  // layers it leaves planar
    // Slab test of the segment against the box (Liang–Barsky).
    double t0 = 0, t1 = 1;
    bool miss = false;
    for (int k = 0; k < 2 && !miss; ++k) {
      const double d = b[k] - a[k];
      if (std::abs(d) < 1e-15) {
        miss = a[k] < r.lo[k] || a[k] > r.hi[k];
        continue;
      }
      double u = (r.lo[k] - a[k]) / d, v = (r.hi[k] - a[k]) / d;
      if (u > v) std::swap(u, v);
      t0 = std::max(t0, u), t1 = std::min(t1, v);
      miss = t0 > t1;
    }
    if (!miss) return false;
  }
  return true;
}

class BandedField::Column {
 public:
  Column(const BandedField& f, double x, double y) : pl_(f.pl_) {
    double sum = 0;
    const std::size_t nb = std::min<std::size_t>(f.bands_.size(), 64);
    for (std::size_t b = 0; b < nb; ++b) {
      const double beta = f.bands_[b].beta(x, y);
      sum += beta;
      if (beta <= 0) continue;
      if (n_ == kMax) {  // more overlapping bands than kept: T evaluates them directly
        field_ = &f, x_ = x, y_ = y;
        break;
      }
      band_[n_] = &f.bands_[b], beta_[n_] = beta, basis_[n_] = f.bands_[b].basis(x, y), ++n_;
    }
    scale_ = sum > 1.0 ? 1.0 / sum : 1.0;
  }
  double T(double z) const {
    if (field_) return field_->T(x_, y_, z);
    double t = pl_.T(z);
    for (int k = 0; k < n_; ++k) {
      const Band& b = *band_[k];
      const double d = b.N < kKept ? b.delta_from([&](int i) { return surface(k, i); }, z, pl_)
                                   : b.delta(basis_[k], z, pl_);
      t += scale_ * beta_[k] * d;
    }
    return t;
  }
  /// Band k's S_i here, each evaluated once per column: a root takes about 5 evaluations of
  /// T, each a binary search over the band's surfaces (9 of them for the bunny's 91 layers),
  /// mostly the same few.
  double surface(int k, int i) const {
    std::uint64_t& word = known_[k][i / 64];
    const std::uint64_t bit = std::uint64_t{1} << (i % 64);
    if (!(word & bit)) kept_[k][i] = band_[k]->surface(basis_[k], i), word |= bit;
    return kept_[k][i];
  }
  bool planar() const { return n_ == 0 && !field_; }
  /// pieces() for a column of one band's own stack (only()), above its top: S_0, S_0 + L_rec
  /// and h₁ if between them (under S_0 z_at's closed form holds).
  bool fade_pieces(std::vector<double>& z, std::vector<std::pair<double, double>>& fading) const {
    if (field_ || n_ != 1 || !(band_[0]->fade > 0)) return false;
    const double S0 = surface(0, 0), top = S0 + band_[0]->fade;
    z = {S0, top};
    if (pl_.h1 > S0 && pl_.h1 < top) z.push_back(pl_.h1);
    fading.emplace_back(S0, top);
    return true;
  }
  /// The heights where T's pieces meet, into `z` (unsorted): h₁, and per band c, S_N … S_0 and
  /// S_0 + L_rec. Between two neighbours T is linear in z (T_p and every δ_b are), except
  /// where a band's δ fades over (S_0, S_0 + L_rec): those spans go to `fading`. False where
  /// that does not hold or is not worth it: more bands than kept, a band of kKept layers or
  /// more, surfaces not strictly decreasing down to c (a zero-thick layer is a step of T, as is
  /// S_N under c by more than rounding), or no fade (a step at S_0).
  bool pieces(std::vector<double>& z, std::vector<std::pair<double, double>>& fading) const {
    if (field_) return false;
    z.push_back(pl_.h1);
    for (int k = 0; k < n_; ++k) {
      const Band& b = *band_[k];
      if (b.N >= kKept || !(b.fade > 0)) return false;
      z.push_back(b.c);
      for (int i = b.N; i >= 0; --i) {
        const double S = surface(k, i);
        // S_N is c up to rounding (1e-15 under it on the sine roof): T steps by as little there.
        if (i == b.N ? !(S >= b.c - 1e-9) : !(S > z.back())) return false;
        z.push_back(S);
      }
      z.push_back(surface(k, 0) + b.fade);
      fading.emplace_back(surface(k, 0), z.back());
    }
    return true;
  }
  /// The one band with β = 1 here when no other band reaches, else null.
  const Band* only(const Band::Basis** basis) const {
    if (field_ || n_ != 1 || beta_[0] < 1 - 1e-12) return nullptr;
    *basis = &basis_[0];
    return band_[0];
  }

 private:
  static constexpr int kMax = 8;
  static constexpr int kKept = 256;  ///< bands of fewer layers keep their surfaces
  const PlanarLayers& pl_;
  const BandedField* field_ = nullptr;  ///< set when more than kMax bands overlap here
  double x_ = 0, y_ = 0, scale_ = 1;
  int n_ = 0;
  const Band* band_[kMax];
  double beta_[kMax];
  Band::Basis basis_[kMax];
  mutable std::uint64_t known_[kMax][kKept / 64] = {};
  mutable double kept_[kMax][kKept];
};

double BandedField::T(double x, double y, double z) const {
  double beta[64], sum = 0;
  const std::size_t nb = std::min<std::size_t>(bands_.size(), 64);
  for (std::size_t b = 0; b < nb; ++b) sum += beta[b] = bands_[b].beta(x, y);
  const double scale = sum > 1.0 ? 1.0 / sum : 1.0;
  double t = pl_.T(z);
  for (std::size_t b = 0; b < nb; ++b)
    if (beta[b] > 0) t += scale * beta[b] * bands_[b].delta(x, y, z, pl_);
  return t;
}

namespace {
constexpr double kNoHint = std::numeric_limits<double>::quiet_NaN();  ///< z_at: no root below

// T over a piece of a column where it is a cubic in z (a band's δ fades by a smoothstep, the
// other terms are linear there): through T at the piece's ends and thirds, in s = (z − za)/w
// with w a third of the piece, by Newton's forward differences (d1, d2, d3 of f0 = T(za)).
struct CubicPiece {
  double za = 0, w = 0, f0 = 0, c1 = 0, c2 = 0, c3 = 0;  ///< T = f0 + c1 s + c2 s² + c3 s³
  CubicPiece(double a, double b, const double f[4]) : za(a), w((b - a) / 3), f0(f[0]) {
    const double d1 = f[1] - f[0], d2 = f[2] - 2 * f[1] + f[0];
    const double d3 = f[3] - 3 * f[2] + 3 * f[1] - f[0];
    c1 = d1 - d2 / 2 + d3 / 3, c2 = d2 / 2 - d3 / 2, c3 = d3 / 6;
  }
  double T(double s) const { return f0 + s * (c1 + s * (c2 + s * c3)); }
  double dT(double s) const { return c1 + s * (2 * c2 + 3 * s * c3); }
  /// z where T = t, T(za) <= t <= T(za + 3w): Newton kept inside a shrinking bracket, to tol.
  double root(double t, double tol) const {
    double lo = 0, hi = 3, s = 1.5;
    for (int it = 0; it < 100; ++it) {
      const double f = T(s) - t, d = dT(s);
      if (f == 0) break;  // else s would close the bracket on itself, and bisect on and on
      (f < 0 ? lo : hi) = s;
      double next = d > 0 ? s - f / d : 0.5 * (lo + hi);
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
      const bool done = std::abs(next - s) * w < 1e-3 * tol || hi - lo < 1e-15;
      s = next;
      if (done) break;
    }
    return za + s * w;
  }
};
}  // namespace

double BandedField::z_at(double x, double y, double t) const {
  return z_at(Column(*this, x, y), t, kNoHint, 1e-10);
}

void BandedField::z_at(double x, double y, const double* t, double* z, int n) const {
  const Column col(*this, x, y);
  for (int i = 0; i < n; ++i) z[i] = z_at(col, t[i], kNoHint, 1e-10);
}

double BandedField::z_at(const Column& col, double t, double lo_hint, double tol) const {
  // Closed forms first: where no band reaches, T is planar; where exactly one band has β = 1
  // (on its patch), T inside the stack is T_bottom + N − s with s the fractional surface
  // index, so z interpolates the two surfaces around s. Everywhere else, root-find.
  if (col.planar()) return pl_.zeta(t);
  const Band::Basis* basis = nullptr;
  if (const Band* only = col.only(&basis)) {
    if (t <= only->T_bottom) return pl_.zeta(t);
    const double s = only->T_bottom + only->N - t;  // 0 at the top surface, N at the plane
    if (s >= 0) {
      const int i = std::min(static_cast<int>(std::floor(s)), only->N - 1);
      const double f = s - i;
      const double Si = only->surface(*basis, i);
      return Si + f * (only->surface(*basis, i + 1) - Si);
    }
  }
  // T increases in z: bracket around the planar guess (from lo_hint when given: a root below
  // this one), then bisection with a secant step (Illinois) to tol.
  const double z0 = pl_.zeta(t);
  double lo = std::isnan(lo_hint) ? z0 - 1.0 : lo_hint, hi = std::max(z0, lo) + 1.0;
  double flo = col.T(lo) - t, fhi = col.T(hi) - t;
  for (int k = 0; flo > 0 && k < 60; ++k) lo -= (hi - lo), flo = col.T(lo) - t;
  for (int k = 0; fhi < 0 && k < 60; ++k) hi += (hi - lo), fhi = col.T(hi) - t;
  return root_in(col, t, lo, hi, flo, fhi, tol);
}

double BandedField::root_in(const Column& col, double t, double lo, double hi, double flo,
                            double fhi, double tol) const {
  int side = 0;
  for (int it = 0; it < 200 && hi - lo > tol; ++it) {
    double z = (lo * fhi - hi * flo) / (fhi - flo);
    if (!(z > lo && z < hi)) z = 0.5 * (lo + hi);
    const double f = col.T(z) - t;
    if (f == 0) return z;
    if ((f < 0) == (flo < 0)) {
      lo = z, flo = f;
      if (side == -1) fhi *= 0.5;
      side = -1;
    } else {
      hi = z, fhi = f;
      if (side == 1) flo *= 0.5;
      side = 1;
    }
  }
  return 0.5 * (lo + hi);
}

void BandedField::z_column(double x, double y, const double* t, double* z, int n,
                           double tol) const {
  const Column col(*this, x, y);
  // Off z_at's closed forms (a band's own stack) T is piecewise polynomial in z
  // (Column::pieces, fade_pieces over a stack's top): T at the ends of its pieces, then each
  // root inside its piece, by interpolation where T is linear and on the cubic through four
  // of its values where a band fades (both exact, to rounding); below and above them all T is
  // T_p. Root-finding each boundary over a stack's top took about 8 evaluations of T each,
  // 190 a column.
  std::vector<double> zs, ts;
  std::vector<std::pair<double, double>> fading;
  std::size_t cubic_at = SIZE_MAX;  // the piece `cubic` is of
  std::optional<CubicPiece> cubic;
  const Band::Basis* basis = nullptr;
  const Band* only = col.only(&basis);
  bool pieced = only ? col.fade_pieces(zs, fading) : !col.planar() && col.pieces(zs, fading);
  if (pieced) {
    std::sort(zs.begin(), zs.end());
    zs.erase(std::unique(zs.begin(), zs.end()), zs.end());
    ts.resize(zs.size());
    for (std::size_t j = 0; j < zs.size(); ++j) ts[j] = col.T(zs[j]);
    pieced = std::is_sorted(ts.begin(), ts.end());
  }
  for (int i = 0; i < n; ++i) {
    const double hint = i > 0 && t[i] >= t[i - 1] ? z[i - 1] : kNoHint;
    if (!pieced || (only && t[i] <= only->T_bottom + only->N)) {
      z[i] = z_at(col, t[i], hint, tol);
      continue;
    }
    // Past the last piece T is T_p; before the first too, unless that is a stack's top (then
    // t is a hair over the stack's T by rounding: root-found).
    if (t[i] > ts.back() || (!only && t[i] < ts.front())) {
      z[i] = pl_.zeta(t[i]);
      continue;
    }
    if (t[i] < ts.front()) {
      z[i] = z_at(col, t[i], hint, tol);
      continue;
    }
    // The piece [zs[j], zs[j + 1]] with T from ts[j] <= t to ts[j + 1] >= t.
    const std::size_t j =
        std::min<std::size_t>(std::upper_bound(ts.begin(), ts.end(), t[i]) - ts.begin(),
                              ts.size() - 1) -
        1;
    const double za = zs[j], zb = zs[j + 1], ta = ts[j], tb = ts[j + 1];
    const bool fades = std::any_of(fading.begin(), fading.end(),
                                   [&](const auto& f) { return za < f.second && zb > f.first; });
    if (!fades) {
      z[i] = tb > ta ? za + (t[i] - ta) * (zb - za) / (tb - ta) : za;
      continue;
    }
    if (cubic_at != j) {
      const double f[4] = {ta, col.T(za + (zb - za) / 3), col.T(za + 2 * (zb - za) / 3), tb};
      cubic.emplace(za, zb, f), cubic_at = j;
    }
    z[i] = cubic->root(t[i], tol);
  }
}

double BandedField::thickness(double x, double y, double z) const {
  const double e = 1e-5;
  const Column col(*this, x, y);
  const double d = (col.T(z + e) - col.T(z - e)) / (2 * e);
  return d > 0 ? 1.0 / d : 1e300;
}

}  // namespace nonplanar::layers
