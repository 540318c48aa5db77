// Height-field fit driver: map the footprint to [0, 1]², fit the polynomial surface, insert
// knots where the residuals exceed the tolerance, then free the weights.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#include "nurbs/fit_internal.hpp"

namespace nonplanar {
namespace {

std::optional<Error> check(const FitParams& p) {
  auto bad = [](const char* key, const char* why) {
    return Error{Status::invalid_argument, std::string(key) + ": " + why};
  };
  if (!std::isfinite(p.tolerance) || p.tolerance <= 0) return bad("fit_tolerance", "must be > 0");
  if (!std::isfinite(p.sample_density) || p.sample_density <= 0 || p.sample_density > 1e4)
    return bad("sample_density", "must be in (0, 1e4] per mm²");
  if (!std::isfinite(p.margin) || p.margin < 0 || p.margin > 1)
    return bad("margin", "must be in [0, 1]");
  if (p.degree < 1 || p.degree > 5) return bad("degree", "must be 1 to 5");
  if (p.initial_spans < 1 || p.initial_spans > 64) return bad("initial_spans", "must be 1 to 64");
  if (p.max_control < p.degree + 1 || p.max_control > 256)
    return bad("max_control", "must be from degree + 1 to 256");
  if (!std::isfinite(p.smoothing) || p.smoothing <= 0) return bad("smoothing", "must be > 0");
  if (!(p.weight_min > 0) || !(p.weight_max > p.weight_min) || !std::isfinite(p.weight_max))
    return bad("weight_min/weight_max", "need 0 < weight_min < weight_max");
  if (p.max_iterations < 0 || p.max_iterations > 10000)
    return bad("max_iterations", "must be 0 to 10000");
  return std::nullopt;
}

// Control-point x, y at the Greville abscissae mapped to the footprint (linear precision).
void place_net(NurbsSurface& s, const Vec2& origin, const Vec2& extent) {
  for (int i = 0; i < s.n_u; ++i) {
    double gu = 0;
    for (int k = 1; k <= s.p; ++k) gu += s.U[i + k];
    gu /= s.p;
    for (int j = 0; j < s.n_v; ++j) {
      double gv = 0;
      for (int k = 1; k <= s.q; ++k) gv += s.V[j + k];
      gv /= s.q;
      Vec3& P = s.points[static_cast<std::size_t>(i) * s.n_v + j];
      P.x() = origin.x() + gu * extent.x();
      P.y() = origin.y() + gv * extent.y();
    }
  }
}

// Spans (in one direction) whose samples miss the targets: local RMS > tol or max > 4 tol.
std::vector<char> spans_to_split(const std::vector<int>& span_of, int n,
                                 const std::vector<double>& r, double tol) {
  std::vector<double> ss(n, 0.0), mx(n, 0.0);
  std::vector<int> cnt(n, 0);
  for (std::size_t k = 0; k < r.size(); ++k) {
    ss[span_of[k]] += r[k] * r[k];
    mx[span_of[k]] = std::max(mx[span_of[k]], std::abs(r[k]));
    ++cnt[span_of[k]];
  }
  std::vector<char> out(n, 0);
  for (int i = 0; i < n; ++i)
    out[i] = cnt[i] > 0 && (std::sqrt(ss[i] / cnt[i]) > tol || mx[i] > 4 * tol);
  return out;
}

}  // namespace

HeightField fit_rectangle(const Vec2& xy_min, const Vec2& xy_max, double margin) {
  HeightField hf;
  const Vec2 size = xy_max - xy_min;
  const Vec2 grow(std::max(0.5, margin * size.x()), std::max(0.5, margin * size.y()));
  hf.origin = xy_min - grow;
  hf.extent = size + 2 * grow;
  return hf;
}

Expected<SurfaceFit> fit_height_field(const std::vector<Vec3>& samples, const Vec2& xy_min,
                                      const Vec2& xy_max, double min_span, const FitParams& params,
                                      const Context& ctx) {
  using namespace nurbs;
  if (auto e = check(params)) return *e;
  const auto t0 = std::chrono::steady_clock::now();
  const int p = params.degree;
  if (samples.size() < 4) return Error{Status::invalid_argument, "fit: fewer than 4 samples"};
  if (!xy_min.allFinite() || !xy_max.allFinite() || !(xy_max.x() > xy_min.x()) ||
      !(xy_max.y() > xy_min.y()))
    return Error{Status::invalid_argument, "fit: the footprint is empty"};

  SurfaceFit out;
  HeightField& hf = out.surface;
  hf = fit_rectangle(xy_min, xy_max, params.margin);
  std::vector<Vec3> uvz(samples.size());
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const Vec2 t = hf.uv(samples[k].x(), samples[k].y());
    uvz[k] = Vec3(t.x(), t.y(), samples[k].z());
  }
  // Density of data per mm² of footprint scales the thin plate so the balance between data
  // and smoothness does not depend on how many samples there are.
  const double lambda =
      params.smoothing * static_cast<double>(samples.size()) / (hf.extent.x() * hf.extent.y());

  NurbsSurface& s = hf.surface;
  s.p = s.q = p;
  // Start no finer than min_span allows.
  auto spans_for = [&](double len) {
    const int by_span = min_span > 0 ? static_cast<int>(len / min_span) : params.initial_spans;
    return std::clamp(std::min(params.initial_spans, by_span), 1, params.max_control - p);
  };
  s.U = uniform_knots(p, spans_for(hf.extent.x()));
  s.V = uniform_knots(p, spans_for(hf.extent.y()));
  s.n_u = static_cast<int>(s.U.size()) - p - 1;
  s.n_v = static_cast<int>(s.V.size()) - p - 1;
  s.points.assign(static_cast<std::size_t>(s.n_u) * s.n_v, Vec3::Zero());
  s.weights.assign(s.points.size(), 1.0);

  SampleBasis basis;
  std::vector<double> r;
  double rms = 0, mx = 0;
  for (;;) {
    if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
    basis.compute(s, uvz);
    if (!fit_polynomial(s, basis, uvz, lambda, hf.extent.x(), hf.extent.y()))
      return Error{Status::internal_error, "fit: least-squares system is singular"};
    rms = residuals(s, basis, uvz, &r, &mx);
    if (rms <= params.tolerance && mx <= 4 * params.tolerance) break;
    // Insert a knot in the middle of every span that misses the targets, if the span is
    // still wider than 2·min_span and the grid has room.
    bool inserted = false;
    for (int dir = 0; dir < 2; ++dir) {
      std::vector<double>& K = dir == 0 ? s.U : s.V;
      const int n = dir == 0 ? s.n_u : s.n_v;
      const double len = dir == 0 ? hf.extent.x() : hf.extent.y();
      const auto split = spans_to_split(dir == 0 ? basis.su : basis.sv, n, r, params.tolerance);
      std::vector<double> mids;
      for (int i = p; i < n; ++i)
        if (split[i] && (K[i + 1] - K[i]) * len >= 2 * min_span)
          mids.push_back(0.5 * (K[i] + K[i + 1]));
      const int room = params.max_control - n;
      if (static_cast<int>(mids.size()) > room) mids.resize(std::max(room, 0));
      for (double m : mids) dir == 0 ? s.insert_knot_u(m) : s.insert_knot_v(m);
      inserted |= !mids.empty();
    }
    if (!inserted) break;
    ++out.refinements;
    ctx.progress("fit", std::min(0.8, 0.1 * out.refinements));
  }
  out.linear_rms = rms;
  const bool met = rms <= params.tolerance && mx <= 4 * params.tolerance;
  const bool refine = !(met && params.refine_only_if_needed);

  if (refine && params.free_weights) {
    fit_rational_linearised(s, basis, uvz, lambda, hf.extent.x(), hf.extent.y(), params);
  }
  if (refine && params.nonlinear != NonlinearSolver::none && params.max_iterations > 0) {
    if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
    NurbsSurface before = s;
    out.nonlinear = fit_nonlinear(s, basis, uvz, lambda, params, ctx);
    if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
    double mx2 = 0;
    const double rms2 = residuals(s, basis, uvz, &r, &mx2);
    // The solver minimises its own regularised cost; keep its result only if the data fit
    // did not get worse.
    if (!(rms2 <= residuals(before, basis, uvz, &r, nullptr) * (1 + 1e-9))) s = before;
  }
  place_net(s, hf.origin, hf.extent);
  out.rms_error = residuals(s, basis, uvz, &r, &out.max_error);
  out.samples = samples.size();
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ctx.progress("fit", 1.0);
  return out;
}

}  // namespace nonplanar
