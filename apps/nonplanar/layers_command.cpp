// `nonplanar layers`: analyse, fit, and build the curved layer stacks and the layer field;
// report the figures, export the layers, the normalised mesh and a cross-section picture.
#include <cstdio>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "nonplanar/deform.hpp"
#include "nonplanar/layers.hpp"
#include "nonplanar/pipeline.hpp"
#include "nonplanar/surface_io.hpp"

namespace nonplanar::cli {
namespace {

struct LayersOptions {
  MeshOptions mesh;
  ProfileOptions profile;
  AnalysisParams analysis;
  FitParams fit;
  LayerParams tuning;  ///< the optimiser's settings (the limits come from the profile)
  bool json = false;
  std::string export_layers, export_normalized, section, at;
};

// The job `slice` would run with the same profile (make_job), the optimiser tuned as asked.
Expected<SliceJob> layers_job(const LayersOptions& o) {
  auto cfg = o.profile.load();
  if (!cfg) return cfg.error();
  // --min-layer-height is the profile's min_layer_height unless the profile sets one.
  if (cfg->min_layer_height == 0)
    cfg->min_layer_height = std::min(o.analysis.min_layer_height, cfg->slice.layer_height);
  if (auto a = check_max_angle(o.analysis.max_angle_deg); !a) return a.error();
  SliceJob job = make_job(*cfg, o.analysis.max_angle_deg);
  AnalysisParams a = o.analysis;
  a.max_angle_deg = job.analysis.max_angle_deg;
  a.min_layer_height = job.analysis.min_layer_height;
  job.analysis = a;
  job.fit = o.fit;
  job.layers.continuity_weight = o.tuning.continuity_weight;
  job.layers.optimizer = o.tuning.optimizer;
  job.layers.max_iterations = o.tuning.max_iterations;
  return job;
}

int run(const LayersOptions& o) {
  std::vector<std::string> inputs = o.profile.config;
  inputs.push_back(o.mesh.model);
  if (auto c = check_outputs(inputs, {o.export_layers, o.export_normalized, o.section}); !c)
    return report_error(c.error());
  auto job = layers_job(o);
  if (!job) return report_error(job.error());
  const LayerParams& lp = job->layers;
  if (!o.mesh.quiet && !o.json)
    for (const Notice& n : job->notices) std::fprintf(stderr, "notice: %s\n", n.text.c_str());
  SectionAt at;
  if (!o.section.empty()) {
    auto a = parse_section_at(o.at);
    if (!a) return report_error(a.error());
    at = *a;
  }
  Context ctx = make_context(o.mesh.quiet || o.json);
  LoadParams load = o.mesh.load;
  load.bed_center = job->print.bed_center();
  auto loaded = load_mesh(o.mesh.model, load, ctx);
  if (!loaded) return finish_progress(), report_error(loaded.error());
  auto analysis = analyze(loaded->mesh, job->analysis, ctx);
  if (!analysis) return finish_progress(), report_error(analysis.error());
  std::vector<int> ids;
  StackCache cache;
  auto fits = fit_for_plan(loaded->mesh, *analysis, job->fit, lp, cache, &ids, ctx);
  if (!fits) return finish_progress(), report_error(fits.error());
  auto plan = plan_layers(loaded->mesh, *analysis, *fits, ids, lp, cache, ctx);
  if (!plan) return finish_progress(), report_error(plan.error());
  std::size_t split = 0;
  if (!o.export_normalized.empty()) {
    auto n = normalize_mesh(loaded->mesh, *plan->field, {}, ctx);
    if (!n) return finish_progress(), report_error(n.error());
    split = n->edges_split;
    if (auto w = write_stl(o.export_normalized, n->mesh); !w)
      return finish_progress(), report_error(w.error());
  }
  finish_progress();
  report_warnings(o.mesh.model, *loaded, o.mesh.quiet);
  if (!o.export_layers.empty()) {
    std::vector<SurfaceRecord> recs;
    for (const LayerStack& st : plan->stacks)
      for (std::size_t i = 0; i < st.surfaces.size(); ++i) {
        SurfaceRecord r;
        r.patch = st.patch;
        r.layer = static_cast<int>(i);
        r.surface = st.surfaces[i];
        r.has_footprint = true;
        r.footprint_min = st.xy_min;
        r.footprint_max = st.xy_max;
        recs.push_back(std::move(r));
      }
    if (auto w = write_surfaces_json(o.export_layers, recs); !w) return report_error(w.error());
  }
  if (!o.section.empty())
    if (auto w = write_section_svg(o.section, loaded->mesh, *plan, at.axis, at.value); !w)
      return report_error(w.error());

  // What `slice` does then: a shell, or shells beside the stacks (it also plans the stacks
  // again on the core's layers and runs the safety check on the result).
  // (Stacks over less than half the curved area: a shell over all the patches is tried first.)
  std::vector<int> stacked;
  double curved = 0, stacked_area = 0;
  for (const Patch& q : analysis->patches) curved += q.needs_nonplanar() ? q.area : 0;
  for (const LayerStack& st : plan->stacks)
    stacked.push_back(st.patch),
        stacked_area += analysis->patches[static_cast<std::size_t>(st.patch)].area;
  if (curved > 2 * stacked_area) stacked.clear();
  const ShellSummary sh = summarize_shell(loaded->mesh, *analysis, lp, stacked);
  if (o.json) {
    nlohmann::ordered_json j;
    j["file"] = o.mesh.model;
    j["params"] = {{"layer_height", lp.layer_height},
                   {"first_layer_height", lp.first_layer_height},
                   {"min_layer_height", lp.min_layer_height},
                   {"max_layer_height", lp.max_layer_height},
                   {"max_angle", lp.max_angle_deg},
                   {"head_reach", lp.toolhead.reach()},
                   {"head_clearance", lp.toolhead.clearance()}};
    nlohmann::ordered_json stacks = nlohmann::ordered_json::array();
    for (const LayerStack& st : plan->stacks)
      stacks.push_back({{"patch", st.patch},
                        {"layers", st.layers},
                        {"c", st.c},
                        {"thickness_min", st.thickness_min},
                        {"thickness_max", st.thickness_max},
                        {"max_slope", st.max_slope_deg},
                        {"max_block_rise", st.max_block_rise},
                        {"cost_before", st.cost_before},
                        {"cost_after", st.cost_after},
                        {"iterations", st.iterations},
                        {"optimizer", st.optimizer_message}});
    j["stacks"] = std::move(stacks);
    nlohmann::ordered_json fb = nlohmann::ordered_json::array();
    for (const auto& f : plan->fallbacks) fb.push_back({{"patch", f.patch}, {"reason", f.reason}});
    j["planar_fallbacks"] = std::move(fb);
    if (!o.export_normalized.empty()) j["normalized_edges_split"] = split;
    if (!sh.patches.empty())
      j["shell"] = {{"patches", sh.patches},         {"shells", sh.shells},
                    {"layers", sh.layers},           {"thickness", sh.thickness},
                    {"core_layers", sh.core_layers}, {"beside_stacks", !stacked.empty()},
                    {"narrowed", sh.narrowed}};
    else if (!sh.refused.empty())
      j["shell"] = {{"refused", sh.refused}};
    std::printf("%s\n", j.dump(2).c_str());
    return kExitOk;
  }
  std::printf("%s: %zu curved stack%s, %zu patch%s kept planar\n", o.mesh.model.c_str(),
              plan->stacks.size(), plan->stacks.size() == 1 ? "" : "s", plan->fallbacks.size(),
              plan->fallbacks.size() == 1 ? "" : "es");
  for (const LayerStack& st : plan->stacks)
    std::printf(
        "  patch %d: %d layers from z = %.2f, thickness %.3f-%.3f mm, steepest %.1f deg, "
        "block rise %.2f mm, cost %.4g -> %.4g (%d iterations)\n",
        st.patch, st.layers, st.c, st.thickness_min, st.thickness_max, st.max_slope_deg,
        st.max_block_rise, st.cost_before, st.cost_after, st.iterations);
  for (const auto& f : plan->fallbacks)
    std::printf("  patch %d planar: %s\n", f.patch, f.reason.c_str());
  const char* beside = stacked.empty() ? "" : " beside the stacks";
  std::string list;
  for (int p : sh.patches) list += (list.empty() ? "" : ", ") + std::to_string(p);
  if (!sh.patches.empty())
    std::printf("  %s%s: patch%s %s as %d curved layers of %.2f mm over %zu planar core layers\n",
                sh.shells > 1 ? (std::to_string(sh.shells) + " shells").c_str() : "shell", beside,
                sh.patches.size() == 1 ? "" : "es", list.c_str(), sh.layers, sh.thickness,
                sh.core_layers);
  if (!sh.narrowed.empty()) std::printf("    not wider: %s\n", sh.narrowed.c_str());
  if (sh.patches.empty() && !sh.refused.empty())
    std::printf("  no shell%s: %s\n", beside, sh.refused.c_str());
  return kExitOk;
}

}  // namespace

void register_layers(CLI::App& app, std::function<int()>* run_fn) {
  auto opts = std::make_shared<LayersOptions>();
  CLI::App* cmd = app.add_subcommand(
      "layers",
      "Build the curved layer stack under every patch (fitted top, plane below, optimised\n"
      "intermediate layers) and the layer field of the whole part; patches whose stack\n"
      "would break a printer limit stay planar, with the reason.");
  opts->mesh.add_to(*cmd);
  add_analysis_options(*cmd, opts->analysis);
  opts->profile.add_to(*cmd, "layer heights, limits, the toolhead; as `slice` reads it");
  LayerParams& l = opts->tuning;
  opts->profile.add_keyed(*cmd, "--layer-height", "layer_height",
                          "Layer height h (mm; default 0.2)");
  opts->profile.add_keyed(*cmd, "--first-layer-height", "first_layer_height", "First layer (mm)");
  opts->profile.add_keyed(*cmd, "--max-layer-height", "max_layer_height",
                          "Thickest curved layer (mm; default automatic, as `slice`)");
  opts->profile.add_keyed(*cmd, "--block-radius", "heater_block_radius",
                          "Heater block radius around the nozzle (mm; = heater_block_radius)");
  opts->profile.add_keyed(
      *cmd, "--block-clearance", "heater_block_clearance",
      "Heater block bottom above the nozzle tip (mm; = heater_block_clearance)");
  cmd->add_option("--continuity-weight", l.continuity_weight, "lambda of the paper's eq. (1)")
      ->capture_default_str();
  const std::map<std::string, StackOptimizer> opt = {{"lbfgs", StackOptimizer::lbfgs},
                                                     {"gd", StackOptimizer::gradient_descent}};
  cmd->add_option("--optimizer", l.optimizer, "lbfgs or gd (gradient descent, eq. 2)")
      ->transform(CLI::CheckedTransformer(opt, CLI::ignore_case))
      ->default_str("lbfgs");
  cmd->add_option("--iterations", l.max_iterations, "Optimiser iterations at most")
      ->capture_default_str();
  cmd->add_option("--fit-tolerance", opts->fit.tolerance, "Surface fit RMS target (mm)")
      ->capture_default_str();
  cmd->add_flag("--json", opts->json, "Print one JSON document");
  cmd->add_option("--export-layers", opts->export_layers,
                  "Write every curved layer surface as JSON (docs/surface-format.md)");
  cmd->add_option("--export-normalized", opts->export_normalized,
                  "Write the normalised mesh (curved layers made planar) as binary STL");
  cmd->add_option("--section", opts->section, "Write a vertical cross-section as SVG");
  cmd->add_option("--at", opts->at, "Where to cut for --section: x=VALUE or y=VALUE (mm)");
  *run_fn = nullptr;
  cmd->callback([opts, run_fn] { *run_fn = [opts] { return run(*opts); }; });
}

}  // namespace nonplanar::cli
