// prepare_part (print_plan.hpp): the slicer's own route, before its slicing: the part to slice
// and the plan post_process_gcode maps its G-code back with.
//
// Notation as in layers/shell_plan.hpp: H the shell's top, N its layers of thickness t,
// z_0 = 0 < … < z_K the core's layer boundaries; z_s = z_K, the core's last.
#include "engine/external_engine.hpp"
#include "engine/shell_engine.hpp"
#include "layers/shell_plan.hpp"
#include "nonplanar/analysis.hpp"
#include "nonplanar/deform.hpp"
#include "nonplanar/field_io.hpp"
#include "nonplanar/print_plan.hpp"
#include "nonplanar/slice.hpp"

namespace nonplanar {
namespace {

// PrintPlan::anchor: the part to slice cut in the middle of its second layer, z0 … z1.
void set_anchor(PrintPlan& p, const TriangleMesh& mesh, double z0, double z1, const Context& ctx) {
  SlicedLayer layer;
  layer.z_bottom = z0, layer.z_top = z1, layer.z_slice = 0.5 * (z0 + z1);
  auto cut = slice_mesh_at(mesh, {layer}, ctx);
  if (!cut || cut->empty()) return;
  double most = 0;
  for (const ExPolygon& island : cut->front().islands)
    if (const double a = area({ExPolygon{island.contour, {}}}); a > most)
      most = a, p.anchor = island.contour;
  p.anchor_z = z1;
}

void set_limits(PrintPlan& p, const SliceJob& job, const SliceResult& r) {
  p.layer_height = job.layers.layer_height;
  p.first_layer_height = job.layers.first_layer_height;
  p.min_layer_height = job.layers.min_layer_height;
  p.max_layer_height = job.layers.max_layer_height;
  p.max_angle_deg = job.layers.max_angle_deg;
  p.toolhead = job.layers.toolhead;
  p.header = r.header;
}

// The box from just above z_s (the slab's first layer is sliced at z_s + t/2, the core's last
// below z_s) to over the top, 1 mm wider than the part: a support blocker there leaves the
// slicer nothing to support under the slab, whose underside floats over the part's top in the
// 3MF (on the rib, supports on printed 53 min of columns against 35 without).
TriangleMesh slab_blocker(const BoundingBox& part, double z_s) {
  const Vec3 lo(part.min.x() - 1, part.min.y() - 1, z_s + 0.01);
  const Vec3 hi(part.max.x() + 1, part.max.y() + 1, part.max.z() + 1);
  TriangleMesh m;
  for (int k = 0; k < 8; ++k)
    m.vertices.emplace_back(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(),
                            k & 4 ? hi.z() : lo.z());
  m.faces = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
             {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

// The shell slice_model printed, for one slicer run: the part as it is, sliced on the core's
// boundaries z_0 … z_s, and above z_s the shell's slab (its normalised layers, ζ = z_s + t + j·t
// … , from ShellField with that base). One layer more under the slab (z_s … z_s + t, the
// normalised part just under the shell's bottom) holds it up, so the slicer prints the slab's
// first layer as it would on the core, not as a bridge over air; post-process cuts that layer
// away. The part's own top above z_s joins the slab's layers there, which cover it (the
// core's layers above z_s are all cut away under the shell). Why not two objects: a slicer
// drops every object onto the bed and prints its first layer with first-layer settings.
Expected<PreparedPart> prepare_shell(const TriangleMesh& placed, const SliceJob& job,
                                     SliceResult& r, const Context& ctx) {
  auto a = analyze(placed, job.analysis, ctx);
  if (!a) return a.error();
  // slice_model printed choose_shells' first, which is choose_shell's (one_run_shells).
  const layers::ShellPlan plan = layers::choose_shell(placed, *a, job.layers);
  if (!plan.refused.empty() || !plan.region.empty() || plan.core.size() < 2)
    return Error{Status::internal_error, "prepare: the shell planned is not the one sliced"};
  const double z_s = plan.core.back(), base = z_s + plan.t;
  const layers::ShellField field(plan, base);
  auto normalized = normalize_mesh(placed, field, shell_normalize_params(placed), ctx);
  if (!normalized) return normalized.error();
  const TriangleMesh slab = cut_below(normalized->mesh, z_s);
  PreparedPart out;
  out.normalized = placed;
  const int offset = static_cast<int>(out.normalized.vertices.size());
  out.normalized.vertices.insert(out.normalized.vertices.end(), slab.vertices.begin(),
                                 slab.vertices.end());
  for (const auto& f : slab.faces)
    out.normalized.faces.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
  std::vector<double> tops(plan.core.begin() + 1, plan.core.end());
  for (int j = 1; j <= plan.N + 1; ++j) tops.push_back(z_s + j * plan.t);
  PrintPlan& p = out.plan;
  p.box = bounding_box(out.normalized);
  out.layer_heights_profile = layer_height_profile(tops, plan.t, p.box.max.z());
  set_limits(p, job, r);
  // The core's layers are the plan's: its first is the slicer's first layer.
  p.first_layer_height = plan.core[1];
  p.layer_height = plan.t;
  auto planar = layer_field_json(*planar_field(job.layers));
  if (!planar) return planar.error();
  p.field = std::move(*planar);
  p.shell = layers::shell_plan_json(plan);
  const double z2 = plan.core.size() > 2 ? plan.core[2] : z_s + plan.t;
  set_anchor(p, out.normalized, plan.core[1], z2, ctx);
  out.support_blocker = slab_blocker(p.box, z_s);
  out.notices = std::move(r.notices);
  out.shell_layers = plan.N;
  return out;
}

}  // namespace

Expected<PreparedPart> prepare_part(const TriangleMesh& placed, SliceJob job, const Context& ctx) {
  job.one_run_shells = true;
  auto r = slice_model(placed, job, ctx);
  if (!r) return r.error();
  if (r->shell_layers > 0) return prepare_shell(placed, job, *r, ctx);
  if (r->plan.stacks.empty() || !r->plan.field) {
    std::string why = "no surface needs curved layers";
    for (const Notice& n : r->notices)
      if (n.kind == Notice::Kind::summary) why = n.text;
    return Error{Status::unsupported,
                 "nothing prints curved, so there is nothing to prepare (" + why +
                     "); slice it as it is ('nonplanar slice' may still print more of its top "
                     "curved: shells beside what stands above them, which one slicer run "
                     "cannot)"};
  }
  auto normalized = normalize_mesh(placed, *r->plan.field, {}, ctx);
  if (!normalized) return normalized.error();
  auto field = layer_field_json(*r->plan.field);
  if (!field) return field.error();
  PreparedPart out;
  out.normalized = std::move(normalized->mesh);
  out.notices = std::move(r->notices);
  out.stacks = r->plan.stacks.size();
  out.field = r->plan.field;
  PrintPlan& p = out.plan;
  p.box = bounding_box(out.normalized);
  set_limits(p, job, *r);
  p.field = std::move(*field);
  set_anchor(p, out.normalized, p.first_layer_height, p.first_layer_height + p.layer_height, ctx);
  return out;
}

}  // namespace nonplanar
