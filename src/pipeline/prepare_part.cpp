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

// The shell slice_model printed, as one slicer run takes it (engine/shell_engine.hpp's
// ShellStack), with the plan post-process splits its G-code by.
Expected<PreparedPart> prepare_shell(const TriangleMesh& placed, const SliceJob& job,
                                     SliceResult& r, const Context& ctx) {
  auto a = analyze(placed, job.analysis, ctx);
  if (!a) return a.error();
  // slice_model printed choose_shells' first, which is choose_shell's (one_run_shells).
  const layers::ShellPlan plan = layers::choose_shell(placed, *a, job.layers, kOneRunShellWhole);
  if (!plan.refused.empty() || !plan.region.empty() || plan.core.size() < 2)
    return Error{Status::internal_error, "prepare: the shell planned is not the one sliced"};
  const double z_s = plan.core.back();
  auto stack = shell_stack(placed, plan, ctx);
  if (!stack) return stack.error();
  PreparedPart out;
  out.normalized = std::move(stack->mesh);
  PrintPlan& p = out.plan;
  p.box = bounding_box(out.normalized);
  out.layer_heights_profile = layer_height_profile(stack->layer_tops, plan.t, p.box.max.z());
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
  out.support_blocker = std::move(stack->support_blocker);
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
