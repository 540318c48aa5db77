// `nonplanar fit`: analyse a model, fit one NURBS height field per patch that needs
// non-planar layers, report the fit quality, and export the surfaces.
#include <cstdio>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "nonplanar/patch_fit.hpp"
#include "nonplanar/surface_io.hpp"

namespace nonplanar::cli {
namespace {

struct FitOptions {
  MeshOptions mesh;
  AnalysisParams analysis;
  FitParams fit;
  bool fixed_weights = false;
  bool json = false;
  std::string export_surfaces, export_mesh;
};

int run(FitOptions o) {
  if (auto c = check_outputs({o.mesh.model}, {o.export_surfaces, o.export_mesh}); !c)
    return report_error(c.error());
  if (o.fixed_weights) o.fit.free_weights = false;
  Context ctx = make_context(o.mesh.quiet || o.json);
  auto loaded = load_mesh(o.mesh.model, o.mesh.load, ctx);
  if (!loaded) {
    finish_progress();
    return report_error(loaded.error());
  }
  auto analysis = analyze(loaded->mesh, o.analysis, ctx);
  if (!analysis) {
    finish_progress();
    return report_error(analysis.error());
  }
  std::vector<SurfaceRecord> records;
  std::vector<SurfaceFit> fits;
  std::vector<int> ids;
  auto fitted = fit_patches(loaded->mesh, *analysis, o.fit, {}, &ids, ctx);
  if (!fitted) {
    finish_progress();
    return report_error(fitted.error());
  }
  fits = std::move(*fitted);
  for (std::size_t k = 0; k < fits.size(); ++k)
    records.push_back({ids[k], fits[k].surface, fits[k].rms_error, fits[k].max_error});
  finish_progress();
  report_warnings(o.mesh.model, *loaded, o.mesh.quiet);
  if (!o.export_surfaces.empty())
    if (auto w = write_surfaces_json(o.export_surfaces, records); !w)
      return report_error(w.error());
  if (!o.export_mesh.empty())
    if (auto w = write_surfaces_obj(o.export_mesh, records); !w) return report_error(w.error());

  if (o.json) {
    nlohmann::ordered_json j;
    j["file"] = o.mesh.model;
    j["params"] = {{"fit_tolerance", o.fit.tolerance},
                   {"sample_density", o.fit.sample_density},
                   {"degree", o.fit.degree},
                   {"free_weights", o.fit.free_weights},
                   {"refine_only_if_needed", o.fit.refine_only_if_needed},
                   {"solver", solver_name(o.fit.nonlinear)}};
    nlohmann::ordered_json arr = nlohmann::ordered_json::array();
    for (std::size_t k = 0; k < fits.size(); ++k) {
      const SurfaceFit& f = fits[k];
      arr.push_back({{"patch", records[k].patch},
                     {"control_grid", {f.surface.surface.n_u, f.surface.surface.n_v}},
                     {"samples", f.samples},
                     {"refinements", f.refinements},
                     {"rms_error", f.rms_error},
                     {"max_error", f.max_error},
                     {"linear_rms", f.linear_rms},
                     {"nonlinear",
                      {{"solver", solver_name(f.nonlinear.solver)},
                       {"iterations", f.nonlinear.iterations},
                       {"initial_cost", f.nonlinear.initial_cost},
                       {"final_cost", f.nonlinear.final_cost},
                       {"termination", f.nonlinear.termination}}},
                     {"seconds", f.seconds}});
    }
    j["surfaces"] = std::move(arr);
    std::printf("%s\n", j.dump(2).c_str());
    return kExitOk;
  }
  std::printf("%s: %zu patch%s non-planar layers; fit tolerance %.4f mm (max %.4f)\n",
              o.mesh.model.c_str(), fits.size(), fits.size() == 1 ? " needs" : "es need",
              o.fit.tolerance, 4 * o.fit.tolerance);
  if (fits.empty()) return kExitOk;
  std::printf("  %5s %9s %8s %10s %10s %7s  %s\n", "patch", "grid", "samples", "rms mm", "max mm",
              "time s", "nonlinear");
  for (std::size_t k = 0; k < fits.size(); ++k) {
    const SurfaceFit& f = fits[k];
    const std::string grid =
        std::to_string(f.surface.surface.n_u) + "x" + std::to_string(f.surface.surface.n_v);
    std::printf("  %5d %9s %8zu %10.5f %10.5f %7.3f  %s, %d iterations, cost %.3g -> %.3g\n",
                records[k].patch, grid.c_str(), f.samples, f.rms_error, f.max_error, f.seconds,
                solver_name(f.nonlinear.solver), f.nonlinear.iterations, f.nonlinear.initial_cost,
                f.nonlinear.final_cost);
  }
  return kExitOk;
}

}  // namespace

void register_fit(CLI::App& app, std::function<int()>* run_fn) {
  auto opts = std::make_shared<FitOptions>();
  CLI::App* cmd = app.add_subcommand(
      "fit",
      "Fit a NURBS height field z = S(x, y) to every patch that needs non-planar layers\n"
      "(least squares with knot refinement, then free weights and a nonlinear refinement).\n"
      "Errors are vertical distances to the patch's triangles, sampled, in mm.");
  opts->mesh.add_to(*cmd);
  add_analysis_options(*cmd, opts->analysis);
  FitParams& f = opts->fit;
  cmd->add_option("--fit-tolerance", f.tolerance, "Target RMS error (mm); max target is 4x")
      ->capture_default_str();
  cmd->add_option("--sample-density", f.sample_density, "Data samples per mm^2 of patch")
      ->capture_default_str();
  cmd->add_option("--degree", f.degree, "Degree in u and v")->capture_default_str();
  cmd->add_option("--max-control", f.max_control, "Control points per direction at most")
      ->capture_default_str();
  cmd->add_flag("--fixed-weights", opts->fixed_weights, "Keep all weights 1 (no rational fit)");
  cmd->add_flag("!--always-refine", f.refine_only_if_needed,
                "Run the rational and nonlinear steps even when the polynomial fit already "
                "meets the tolerance");
  const std::map<std::string, NonlinearSolver> solvers = {
      {"lm", NonlinearSolver::levenberg_marquardt},
      {"gn", NonlinearSolver::gauss_newton_line_search},
      {"none", NonlinearSolver::none}};
  cmd->add_option("--solver", f.nonlinear,
                  "Nonlinear refinement: lm (Levenberg-Marquardt, Ceres), gn (Gauss-Newton with "
                  "line search) or none")
      ->transform(CLI::CheckedTransformer(solvers, CLI::ignore_case))
      ->default_str("lm");
  cmd->add_flag("--json", opts->json, "Print one JSON document instead of the table");
  cmd->add_option("--export-surfaces", opts->export_surfaces,
                  "Write the surfaces as JSON (format: docs/surface-format.md)");
  cmd->add_option("--export-mesh", opts->export_mesh,
                  "Write the surfaces tessellated over their footprints as OBJ");
  *run_fn = nullptr;
  cmd->callback([opts, run_fn] { *run_fn = [opts] { return run(*opts); }; });
}

}  // namespace nonplanar::cli
