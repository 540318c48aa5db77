#include "layers/printability_cost.hpp"
#include "core/parallel.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "nurbs/bspline_basis.hpp"

namespace nonplanar::layers {

void StackGrid::pair_within(double radius, double spacing) {
  block_pairs.clear();
  const int sx = std::max(1, static_cast<int>(std::lround(spacing / step_x)));
  const int sy = std::max(1, static_cast<int>(std::lround(spacing / step_y)));
  const int rx = static_cast<int>(radius / (sx * step_x)),
            ry = static_cast<int>(radius / (sy * step_y));
  for (int a = 0; a < nx; a += sx)
    for (int b = 0; b < ny; b += sy) {
      const int k = a * ny + b;
      if (!on_patch[k]) continue;
      for (int di = -rx; di <= rx; ++di)
        for (int dj = -ry; dj <= ry; ++dj) {
          const int a2 = a + di * sx, b2 = b + dj * sy;
          if ((di == 0 && dj == 0) || a2 < 0 || b2 < 0 || a2 >= nx || b2 >= ny) continue;
          if (std::hypot(di * sx * step_x, dj * sy * step_y) > radius) continue;
          const int l = a2 * ny + b2;
          if (on_patch[l]) block_pairs.emplace_back(k, l);
        }
    }
}

void build_stack_grid(StackGrid& g, const HeightField& hf, double step,
                      const std::vector<char>& raster_mask, const Vec2& raster_origin,
                      double raster_cell, int raster_nx, int raster_ny) {
  const NurbsSurface& s = hf.surface;
  g = StackGrid{};
  g.m = (s.p + 1) * (s.q + 1);
  const int nx = std::max(2, static_cast<int>(std::ceil(hf.extent.x() / step)));
  const int ny = std::max(2, static_cast<int>(std::ceil(hf.extent.y() / step)));
  const double dx = hf.extent.x() / nx, dy = hf.extent.y() / ny;
  g.nx = nx, g.ny = ny, g.step_x = dx, g.step_y = dy;
  std::vector<double> du(2 * (s.p + 1)), dv(2 * (s.q + 1));
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) {
      const double x = hf.origin.x() + (i + 0.5) * dx, y = hf.origin.y() + (j + 0.5) * dy;
      const int ri = static_cast<int>(std::lround((x - raster_origin.x()) / raster_cell));
      const int rj = static_cast<int>(std::lround((y - raster_origin.y()) / raster_cell));
      const bool on = ri >= 0 && rj >= 0 && ri < raster_nx && rj < raster_ny &&
                      raster_mask[static_cast<std::size_t>(ri) * raster_ny + rj];
      g.xy.emplace_back(x, y);
      g.area.push_back(dx * dy);
      g.on_patch.push_back(on);
      if (s.points.empty()) continue;  // not fitted yet: the points only
      const Vec2 uv = hf.uv(x, y);
      const int su = nurbs::find_span(s.n_u, s.p, uv.x(), s.U);
      const int sv = nurbs::find_span(s.n_v, s.q, uv.y(), s.V);
      nurbs::ders_basis_funs(su, uv.x(), s.p, 1, s.U, du.data());
      nurbs::ders_basis_funs(sv, uv.y(), s.q, 1, s.V, dv.data());
      for (int a = 0; a <= s.p; ++a)
        for (int c = 0; c <= s.q; ++c) g.ctrl.push_back((su - s.p + a) * s.n_v + (sv - s.q + c));
      // Rational basis R = N w / W and its derivatives (quotient rule), in x and y.
      double W = 0, Wu = 0, Wv = 0;
      for (int a = 0; a <= s.p; ++a)
        for (int c = 0; c <= s.q; ++c) {
          const double w = s.w(su - s.p + a, sv - s.q + c);
          W += du[a] * dv[c] * w;
          Wu += du[s.p + 1 + a] * dv[c] * w;
          Wv += du[a] * dv[s.q + 1 + c] * w;
        }
      for (int a = 0; a <= s.p; ++a)
        for (int c = 0; c <= s.q; ++c) {
          const double w = s.w(su - s.p + a, sv - s.q + c);
          const double N = du[a] * dv[c] * w, Nu = du[s.p + 1 + a] * dv[c] * w,
                       Nv = du[a] * dv[s.q + 1 + c] * w;
          g.R.push_back(N / W);
          g.Rx.push_back((Nu * W - N * Wu) / (W * W) / hf.extent.x());
          g.Ry.push_back((Nv * W - N * Wv) / (W * W) / hf.extent.y());
        }
    }
}

double printability_cost(const StackGrid& g, const Eigen::MatrixXd& Z, const CostTerms& c,
                         Eigen::MatrixXd* grad) {
  const int L = static_cast<int>(Z.rows());  // N + 1 surfaces
  const int n = static_cast<int>(g.xy.size());
  if (grad) grad->setZero(L - 2 > 0 ? L - 2 : 0, Z.cols());
  // Heights of every layer at every sample, kept for the heater-block pairs below.
  const bool pairs = c.clearance < 1e299 && !g.block_pairs.empty() && L > 2;
  std::vector<double> all(pairs ? static_cast<std::size_t>(L) * n : 0);
  // The samples in a fixed number of chunks, in parallel; partial sums are added in chunk
  // order, so the result does not depend on the threads.
  constexpr int kChunks = 16;
  std::array<double, kChunks> part{};
  std::array<Eigen::MatrixXd, kChunks> part_grad;
  core::parallel_for(0, kChunks, [&](int ch) {
    double cost = 0;
    Eigen::MatrixXd* gr = nullptr;
    if (grad) part_grad[ch].setZero(grad->rows(), grad->cols()), gr = &part_grad[ch];
    std::vector<double> S(L), Sx(L), Sy(L), dS(L), dSx(L), dSy(L);
    const int k0 = static_cast<int>(static_cast<long>(n) * ch / kChunks);
    const int k1 = static_cast<int>(static_cast<long>(n) * (ch + 1) / kChunks);
    for (int k = k0; k < k1; ++k) {
      // Every term is the patch's (see the limits below), and so is every heater-block pair:
      // a sample off the patch adds nothing (a fifth of the sphere's).
      if (!g.on_patch[k]) continue;
      const double* R = &g.R[static_cast<std::size_t>(k) * g.m];
      const double* Rx = &g.Rx[static_cast<std::size_t>(k) * g.m];
      const double* Ry = &g.Ry[static_cast<std::size_t>(k) * g.m];
      const int* C = &g.ctrl[static_cast<std::size_t>(k) * g.m];
      // Basis function by basis function, down a control's column of Z (its layers lie next
      // to each other): each S_i is still summed in the order of a.
      std::fill(S.begin(), S.end(), 0.0), std::fill(Sx.begin(), Sx.end(), 0.0);
      std::fill(Sy.begin(), Sy.end(), 0.0);
      for (int a = 0; a < g.m; ++a) {
        const double* z = &Z(0, C[a]);
        const double r = R[a], rx = Rx[a], ry = Ry[a];
        for (int i = 0; i < L; ++i) S[i] += r * z[i], Sx[i] += rx * z[i], Sy[i] += ry * z[i];
      }
      for (int i = 0; i < L; ++i) {
        if (pairs) all[static_cast<std::size_t>(i) * n + k] = S[i];
        dS[i] = dSx[i] = dSy[i] = 0;
      }
      const double ak = g.area[k];
      for (int i = 0; i + 1 < L; ++i) {
        const double t = S[i] - S[i + 1];
        double dt = 0;  // ∂C/∂t
        cost += ak * (t - c.h) * (t - c.h);
        dt += 2 * ak * (t - c.h);
        const double ex = Sx[i] - Sx[i + 1], ey = Sy[i] - Sy[i + 1];
        cost += ak * c.lambda * (ex * ex + ey * ey);
        dSx[i] += 2 * ak * c.lambda * ex, dSx[i + 1] -= 2 * ak * c.lambda * ex;
        dSy[i] += 2 * ak * c.lambda * ey, dSy[i + 1] -= 2 * ak * c.lambda * ey;
        if (t < c.h_min)
          cost += ak * c.mu * (c.h_min - t) * (c.h_min - t), dt -= 2 * ak * c.mu * (c.h_min - t);
        if (t > c.h_max)
          cost += ak * c.mu * (t - c.h_max) * (t - c.h_max), dt += 2 * ak * c.mu * (t - c.h_max);
        dS[i] += dt, dS[i + 1] -= dt;
      }
      // The top is fixed (the part) and the bottom is flat. Off the patch the fit is held only
      // by its smoothness and can swing by millimetres, so its layers there broke the limits
      // with penalties no move could lift (FoilCutter: 2.6e9 at the start): the optimiser then
      // bent the layers over the patch after them and its result was thrown away (13 of 25
      // stacks on 12 real parts). Limits are the stack's over the patch, as the stack's
      // figures measure them; the blend check judges the layers round it.
      // Most layers are well under the limit: the square screens them (with room for its
      // rounding) before the exact hypot, which was a tenth of an evaluation. (g < 0, under
      // 0.6° max_angle: nothing is screened.)
      const double g2 = c.g > 0 ? c.g * c.g * (1 - 1e-9) : -1.0;
      for (int i = 1; i + 1 < L; ++i) {
        if (Sx[i] * Sx[i] + Sy[i] * Sy[i] <= g2) continue;
        const double sl = std::hypot(Sx[i], Sy[i]);
        if (sl > c.g) {
          cost += ak * c.mu * (sl - c.g) * (sl - c.g);
          const double f = 2 * ak * c.mu * (sl - c.g) / sl;
          dSx[i] += f * Sx[i], dSy[i] += f * Sy[i];
        }
      }
      if (!gr) continue;
      // Each (layer, control) gets one term per sample, in sample order, as before the loops
      // were swapped; layers with no term are left alone.
      for (int a = 0; a < g.m; ++a) {
        double* gc = gr->data() + static_cast<std::size_t>(C[a]) * gr->rows();  // column
        const double r = R[a], rx = Rx[a], ry = Ry[a];
        for (int i = 1; i + 1 < L; ++i)
          if (dS[i] != 0 || dSx[i] != 0 || dSy[i] != 0)
            gc[i - 1] += dS[i] * r + dSx[i] * rx + dSy[i] * ry;
      }
    }
    part[ch] = cost;
  });
  double cost = 0;
  for (int ch = 0; ch < kChunks; ++ch) {
    cost += part[ch];
    if (grad) *grad += part_grad[ch];
  }
  // Heater block: a layer may not rise more than H within the block radius. Only the
  // intermediate layers are free; the top is the part and the bottom is flat. Layer i's terms
  // touch only row i − 1 of the gradient, so the layers go in parallel; their sums are added
  // in layer order (the bunny's largest patch: 91 layers × 42698 pairs, 100 iterations).
  if (pairs) {
    std::vector<double> layer_cost(static_cast<std::size_t>(L), 0.0);
    core::parallel_for(1, L - 1, [&](int i) {
      const double* Si = &all[static_cast<std::size_t>(i) * n];
      double sum = 0;
      for (const auto& [k, l] : g.block_pairs) {
        const double over = Si[l] - Si[k] - c.clearance;
        if (over <= 0) continue;
        const double w = g.area[k];
        sum += w * c.mu * over * over;
        if (!grad) continue;
        const double d = 2 * w * c.mu * over;
        for (int a = 0; a < g.m; ++a) {
          (*grad)(i - 1, g.control(l, a)) += d * g.R[static_cast<std::size_t>(l) * g.m + a];
          (*grad)(i - 1, g.control(k, a)) -= d * g.R[static_cast<std::size_t>(k) * g.m + a];
        }
      }
      layer_cost[static_cast<std::size_t>(i)] = sum;
    });
    for (int i = 1; i + 1 < L; ++i) cost += layer_cost[static_cast<std::size_t>(i)];
  }
  return cost;
}

}  // namespace nonplanar::layers
