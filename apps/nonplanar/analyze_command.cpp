// `nonplanar analyze`: load a model, select printable facets, split them into patches and
// report them (text or JSON), optionally exporting a PLY coloured by patch.
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "nonplanar/analysis.hpp"

namespace nonplanar::cli {
namespace {

struct AnalyzeOptions {
  MeshOptions mesh;
  AnalysisParams params;
  bool json = false;
  std::string export_patches;
};

// Distinct, bright colours by golden-ratio hue steps.
unsigned patch_color(int i) {
  const double h = std::fmod(0.13 + 0.618033988749895 * i, 1.0) * 6.0;
  const double x = 1.0 - std::abs(std::fmod(h, 2.0) - 1.0);
  double r = 0, g = 0, b = 0;
  switch (static_cast<int>(h)) {
    case 0:
      r = 1, g = x;
      break;
    case 1:
      r = x, g = 1;
      break;
    case 2:
      g = 1, b = x;
      break;
    case 3:
      g = x, b = 1;
      break;
    case 4:
      r = x, b = 1;
      break;
    default:
      r = 1, b = x;
      break;
  }
  auto c = [](double v) { return static_cast<unsigned>(60 + 195 * v); };
  return (c(r) << 16) | (c(g) << 8) | c(b);
}

nlohmann::ordered_json to_json(const AnalyzeOptions& o, const LoadedMesh& m, const Analysis& a) {
  using nlohmann::ordered_json;
  const BoundingBox box = bounding_box(m.mesh);
  const MeshDefects& d = m.defects;
  ordered_json j;
  j["file"] = o.mesh.model;
  j["format"] = format_name(m.format);
  j["mesh"] = {{"input_triangles", m.input_triangles},
               {"triangles", m.mesh.faces.size()},
               {"vertices", m.mesh.vertices.size()},
               {"size", {box.size().x(), box.size().y(), box.size().z()}},
               {"bbox_min", {box.min.x(), box.min.y(), box.min.z()}},
               {"bbox_max", {box.max.x(), box.max.y(), box.max.z()}},
               {"volume", signed_volume(m.mesh)},
               {"weld_tolerance", m.weld_tolerance}};
  j["defects"] = {{"open_edges", d.open_edges},
                  {"non_manifold_edges", d.non_manifold_edges},
                  {"inconsistent_edges", d.inconsistent_edges},
                  {"zero_area_faces", d.zero_area_faces},
                  {"collapsed_faces", d.collapsed_faces},
                  {"shells", d.shells},
                  {"faces_flipped", d.faces_flipped},
                  {"was_inverted", d.was_inverted},
                  {"closed", d.closed()}};
  j["params"] = {{"max_angle", o.params.max_angle_deg},
                 {"tau", o.params.tau},
                 {"epsilon", o.params.epsilon},
                 {"crease_angle", o.params.crease_angle_deg},
                 {"min_layer_height", o.params.min_layer_height},
                 {"min_patch_area", o.params.min_patch_area}};
  j["painted_faces"] = a.painted_faces;
  j["discontinuous_faces"] = a.discontinuous_faces;
  j["crease_edges"] = a.crease_edges;
  std::size_t n_np = 0;
  ordered_json patches = ordered_json::array();
  for (std::size_t i = 0; i < a.patches.size(); ++i) {
    const Patch& p = a.patches[i];
    n_np += p.needs_nonplanar();
    patches.push_back({{"id", i},
                       {"faces", p.faces.size()},
                       {"area", p.area},
                       {"xy_min", {p.xy_min.x(), p.xy_min.y()}},
                       {"xy_max", {p.xy_max.x(), p.xy_max.y()}},
                       {"z_min", p.z_min},
                       {"z_max", p.z_max},
                       {"max_slope", p.max_slope_deg},
                       {"needs_nonplanar", p.needs_nonplanar()},
                       {"verdict", verdict_name(p.verdict)}});
  }
  j["nonplanar_patches"] = n_np;
  j["patches"] = std::move(patches);
  return j;
}

void print_text(const AnalyzeOptions& o, const LoadedMesh& m, const Analysis& a) {
  const BoundingBox box = bounding_box(m.mesh);
  const MeshDefects& d = m.defects;
  std::printf("%s (%s): %zu triangles, %zu vertices, %zu shell%s, %s\n", o.mesh.model.c_str(),
              format_name(m.format), m.mesh.faces.size(), m.mesh.vertices.size(), d.shells,
              d.shells == 1 ? "" : "s", d.closed() ? "closed" : "NOT closed");
  std::printf(
      "size %.2f x %.2f x %.2f mm, volume %.1f mm^3, placed with centre (%.1f, %.1f), z from 0\n",
      box.size().x(), box.size().y(), box.size().z(), signed_volume(m.mesh),
      o.mesh.load.bed_center.x(), o.mesh.load.bed_center.y());
  std::printf("painted faces (slope < %.1f deg): %zu of %zu; discontinuous %zu; crease edges %zu\n",
              o.params.max_angle_deg, a.painted_faces, m.mesh.faces.size(), a.discontinuous_faces,
              a.crease_edges);
  std::size_t n_np = 0;
  for (const Patch& p : a.patches) n_np += p.needs_nonplanar();
  std::printf("patches: %zu, of which %zu need non-planar layers\n", a.patches.size(), n_np);
  if (a.patches.empty()) return;
  std::printf("  %4s %7s %10s %19s %19s %15s %9s  %s\n", "id", "faces", "area mm2", "x range mm",
              "y range mm", "z range mm", "slope deg", "verdict");
  for (std::size_t i = 0; i < a.patches.size(); ++i) {
    const Patch& p = a.patches[i];
    std::printf("  %4zu %7zu %10.2f %9.2f-%-9.2f %9.2f-%-9.2f %7.2f-%-7.2f %9.1f  %s\n", i,
                p.faces.size(), p.area, p.xy_min.x(), p.xy_max.x(), p.xy_min.y(), p.xy_max.y(),
                p.z_min, p.z_max, p.max_slope_deg, verdict_name(p.verdict));
  }
}

int run(const AnalyzeOptions& o) {
  if (auto c = check_outputs({o.mesh.model}, {o.export_patches}); !c)
    return report_error(c.error());
  Context ctx = make_context(o.mesh.quiet || o.json);
  auto loaded = load_mesh(o.mesh.model, o.mesh.load, ctx);
  if (!loaded) {
    finish_progress();
    return report_error(loaded.error());
  }
  auto analysis = analyze(loaded->mesh, o.params, ctx);
  finish_progress();
  if (!analysis) return report_error(analysis.error());
  report_warnings(o.mesh.model, *loaded, o.mesh.quiet);
  if (!o.export_patches.empty()) {
    std::vector<unsigned> colors(loaded->mesh.faces.size(), 0xb4b4b4);  // grey: not painted
    for (std::size_t f = 0; f < colors.size(); ++f) {
      if (analysis->face_patch[f] >= 0)
        colors[f] = analysis->patches[analysis->face_patch[f]].needs_nonplanar()
                        ? patch_color(analysis->face_patch[f])
                        : 0x6080a0;  // flat or tiny patch: muted blue
      else if (analysis->painted[f])
        colors[f] = 0x202020;  // painted but discontinuous: near black
    }
    if (auto w = write_ply_face_colors(o.export_patches, loaded->mesh, colors); !w)
      return report_error(w.error());
  }
  if (o.json)
    std::printf("%s\n", to_json(o, *loaded, *analysis).dump(2).c_str());
  else
    print_text(o, *loaded, *analysis);
  return kExitOk;
}

}  // namespace

void register_analyze(CLI::App& app, std::function<int()>* run_fn) {
  auto opts = std::make_shared<AnalyzeOptions>();
  CLI::App* cmd = app.add_subcommand(
      "analyze",
      "Find the faces a nozzle can follow (slope below --max-angle) and split them into\n"
      "patches at curvature discontinuities and creases; print the patches.");
  opts->mesh.add_to(*cmd);
  add_analysis_options(*cmd, opts->params);
  cmd->add_flag("--json", opts->json, "Print one JSON document instead of the summary");
  cmd->add_option("--export-patches", opts->export_patches,
                  "Write the mesh as PLY with one colour per patch (grey: not printable "
                  "non-planar, black: discontinuous, blue: flat or too small)");
  *run_fn = nullptr;
  cmd->callback([opts, run_fn] { *run_fn = [opts] { return run(*opts); }; });
}

}  // namespace nonplanar::cli
