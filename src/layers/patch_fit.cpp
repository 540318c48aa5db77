// A surface per patch: samples of its triangles as the fit's data, and the fit's error
// measured against them.
#include <algorithm>
#include <cmath>

#include "nonplanar/patch_fit.hpp"

namespace nonplanar {
namespace {

// Calls f(point) for the vertices of the patch (once each) and for `density`·area points
// per triangle, placed on a regular barycentric lattice (deterministic, area-weighted).
template <class F>
void for_each_sample(const TriangleMesh& mesh, const Patch& patch, double density, F&& f) {
  std::vector<char> seen(mesh.vertices.size(), 0);
  for (int fi : patch.faces)
    for (int v : mesh.faces[fi])
      if (!seen[v]) seen[v] = 1, f(mesh.vertices[v]);
  for (int fi : patch.faces) {
    const auto& t = mesh.faces[fi];
    const Vec3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
    const double area = 0.5 * (b - a).cross(c - a).norm();
    // A lattice of m rows holds m(m+1)/2 interior points: choose m for density · area.
    const int m = static_cast<int>(std::floor((std::sqrt(8 * density * area + 1) - 1) / 2));
    for (int i = 0; i < m; ++i)
      for (int j = 0; i + j < m; ++j) {
        const double u = (i + 1.0 / 3.0) / m, v = (j + 1.0 / 3.0) / m;
        f(a + u * (b - a) + v * (c - a));
      }
  }
}

}  // namespace

std::vector<Vec3> sample_patch(const TriangleMesh& mesh, const Patch& patch, double density) {
  std::vector<Vec3> out;
  for_each_sample(mesh, patch, density, [&](const Vec3& p) { out.push_back(p); });
  return out;
}

FitError measure_fit_error(const HeightField& s, const TriangleMesh& mesh, const Patch& patch,
                           double density) {
  FitError e;
  double ss = 0;
  for_each_sample(mesh, patch, density, [&](const Vec3& p) {
    const double d = std::abs(s.height(p.x(), p.y()) - p.z());
    ss += d * d;
    e.max = std::max(e.max, d);
    ++e.samples;
  });
  e.rms = e.samples ? std::sqrt(ss / static_cast<double>(e.samples)) : 0.0;
  return e;
}

Expected<std::vector<SurfaceFit>> fit_patches(const TriangleMesh& mesh, const Analysis& analysis,
                                              const FitParams& params, const std::vector<int>& skip,
                                              std::vector<int>* patch_ids, const Context& ctx) {
  ctx.progress("fit", 0);
  std::vector<SurfaceFit> fits;
  patch_ids->clear();
  for (std::size_t i = 0; i < analysis.patches.size(); ++i) {
    if (!analysis.patches[i].needs_nonplanar()) continue;
    if (std::find(skip.begin(), skip.end(), static_cast<int>(i)) != skip.end()) continue;
    auto f = fit_patch(mesh, analysis.patches[i], params, ctx);
    if (!f) return f.error();
    fits.push_back(std::move(*f));
    patch_ids->push_back(static_cast<int>(i));
  }
  return fits;
}

Expected<SurfaceFit> fit_patch(const TriangleMesh& mesh, const Patch& patch,
                               const FitParams& params, const Context& ctx) {
  if (patch.faces.empty()) return Error{Status::invalid_argument, "fit: empty patch"};
  std::vector<double> edges;
  for (int fi : patch.faces)
    for (int k = 0; k < 3; ++k)
      edges.push_back(
          (mesh.vertices[mesh.faces[fi][k]] - mesh.vertices[mesh.faces[fi][(k + 1) % 3]])
              .head<2>()
              .norm());
  std::nth_element(edges.begin(), edges.begin() + edges.size() / 2, edges.end());
  // Knots closer than the mesh's own edges would fit its facets, not the surface.
  const double min_span = edges[edges.size() / 2];
  auto fit = fit_height_field(sample_patch(mesh, patch, params.sample_density), patch.xy_min,
                              patch.xy_max, min_span, params, ctx);
  if (!fit) return fit;
  const FitError e = measure_fit_error(fit->surface, mesh, patch, 4 * params.sample_density);
  fit->rms_error = e.rms;
  fit->max_error = e.max;
  return fit;
}

}  // namespace nonplanar
