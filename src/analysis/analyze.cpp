#include <cmath>
#include <optional>
#include <string>

#include "analysis/creases.hpp"
#include "analysis/curvature.hpp"
#include "analysis/patches.hpp"
#include "nonplanar/analysis.hpp"

namespace nonplanar {

const char* verdict_name(PatchVerdict v) {
  switch (v) {
    case PatchVerdict::nonplanar:
      return "non-planar";
    case PatchVerdict::flat:
      return "flat";
    case PatchVerdict::too_small:
      return "too small";
  }
  return "unknown";
}

namespace {

std::optional<Error> check_params(const AnalysisParams& p) {
  auto bad = [](const char* key, const char* why) {
    return Error{Status::invalid_argument, std::string(key) + ": " + why};
  };
  if (!std::isfinite(p.max_angle_deg) || p.max_angle_deg <= 0 || p.max_angle_deg >= 90)
    return bad("max_angle", "must be in (0, 90) degrees");
  if (!std::isfinite(p.tau) || p.tau < 0) return bad("tau", "must be a finite number >= 0");
  if (!std::isfinite(p.epsilon) || p.epsilon < 0)
    return bad("epsilon", "must be a finite number >= 0");
  if (!std::isfinite(p.crease_angle_deg) || p.crease_angle_deg <= 0 || p.crease_angle_deg >= 180)
    return bad("crease_angle", "must be in (0, 180) degrees");
  if (!std::isfinite(p.min_layer_height) || p.min_layer_height <= 0)
    return bad("min_layer_height", "must be a finite number > 0");
  if (!std::isfinite(p.min_patch_area) || p.min_patch_area < 0)
    return bad("min_patch_area", "must be a finite number >= 0");
  return std::nullopt;
}

}  // namespace

Expected<Analysis> analyze(const TriangleMesh& mesh, const AnalysisParams& params,
                           const Context& ctx) {
  ctx.progress("analyze", 0);
  using namespace analysis;
  if (auto e = check_params(params)) return *e;
  constexpr double kDeg = M_PI / 180.0;
  const MeshTopology topo = build_topology(mesh);
  const FaceGeometry geom = face_geometry(mesh);
  ctx.progress("analyze", 0.3);
  if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};

  Analysis out;
  out.painted = select_facets(geom, topo, params.max_angle_deg * kDeg);
  for (char p : out.painted) out.painted_faces += p != 0;

  const VertexCurvature curv = angle_deficit(mesh, topo, geom, &out.painted);
  out.curvature = curv.normalized();
  const std::vector<char> vdisc =
      discontinuous_vertices(mesh, curv, out.painted, params.tau, params.epsilon);
  out.discontinuous.assign(mesh.faces.size(), 0);
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    if (!out.painted[f]) continue;
    const auto& t = mesh.faces[f];
    out.discontinuous[f] = vdisc[t[0]] || vdisc[t[1]] || vdisc[t[2]];
    out.discontinuous_faces += out.discontinuous[f] != 0;
  }
  ctx.progress("analyze", 0.7);
  if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};

  const std::vector<char> crease =
      find_creases(topo, geom, out.painted, params.crease_angle_deg * kDeg);
  for (std::size_t c = 0; c < crease.size(); ++c)
    if (crease[c] && static_cast<int>(c / 3) < topo.across[c]) ++out.crease_edges;
  out.patches = extract_patches(mesh, topo, geom, out.painted, out.discontinuous, crease, params,
                                &out.face_patch);
  ctx.progress("analyze", 1.0);
  return out;
}

}  // namespace nonplanar
