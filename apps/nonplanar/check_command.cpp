// `nonplanar check`: the quality figures of DESIGN.md §4 from a G-code file (ours or
// PrusaSlicer's) and the mesh it was sliced from.
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli_common.hpp"
#include "commands.hpp"
#include "core/file_bytes.hpp"
#include "nonplanar/check.hpp"
#include "nonplanar/gcode.hpp"

namespace nonplanar::cli {
namespace {

struct CheckOptions {
  MeshOptions mesh;
  ProfileOptions profile;
  std::string gcode;
  double max_angle = 30;
  double min_angle = 0;
  double tolerance = 0.03;
  bool json = false;
};

int run(const CheckOptions& o) {
  if (auto a = check_max_angle(o.max_angle); !a) return report_error(a.error());
  auto bytes = core::read_file_bytes(o.gcode, 2ull << 30);
  if (!bytes) return report_error({bytes.error().status, o.gcode + ": " + bytes.error().message});
  // The file's own settings first; presets, --config and --set go over them.
  auto cfg = o.profile.load(file_config(o.gcode, bytes->view(), o.mesh.quiet || o.json));
  if (!cfg) return report_error(cfg.error());
  if (!(o.min_angle >= 0 && o.min_angle < o.max_angle))
    return report_error(
        {Status::invalid_argument, "--min-angle: must be at least 0 and below --max-angle"});
  if (!(o.tolerance > 0 && o.tolerance < 100))
    return report_error({Status::invalid_argument, "--tolerance: must be in (0, 100) mm"});
  CheckParams params = check_params(*cfg, o.max_angle);
  params.min_angle_deg = o.min_angle;
  params.within_tolerance = o.tolerance;
  Context ctx = make_context(o.mesh.quiet || o.json);
  auto moves = read_gcode_moves(bytes->view());
  if (!moves)
    return finish_progress(),
           report_error({moves.error().status, o.gcode + ": " + moves.error().message});
  const LoadParams lp = o.mesh.placed_like(bytes->view(), *cfg, o.mesh.quiet || o.json);
  auto mesh = load_mesh(o.mesh.model, lp, ctx);
  if (!mesh) return finish_progress(), report_error(mesh.error());
  auto f = check_print(*moves, &mesh->mesh, params, ctx);
  finish_progress();
  if (!f) return report_error({f.error().status, o.gcode + ": " + f.error().message});
  // All figures 0 would read as a pass: an empty file, one without ;LAYER_CHANGE, lowercase
  // or CR-only lines measure nothing, and say so.
  if (f->extrusions == 0)
    return report_error({Status::invalid_argument,
                         o.gcode + ": no extrusion after a ;LAYER_CHANGE comment, so nothing "
                                   "was measured (check reads the G-code of nonplanar, "
                                   "PrusaSlicer and OrcaSlicer)"});
  // The time with the file's own limits (its settings block, M201-M205), as PrusaSlicer's
  // viewer estimates it.
  const GcodeProgram program = read_gcode_program(bytes->view());
  const double seconds = estimate_print_time(program, machine_limits(*cfg)).total;
  // And the stealth mode's, where PrusaSlicer estimates one (the MK3S's silent_mode).
  const double silent =
      silent_mode_estimate(*cfg) ? estimate_print_time(program, machine_limits(*cfg, 1)).total : -1;
  if (o.json) {
    nlohmann::ordered_json j = {
        {"gcode", o.gcode},
        {"mesh", o.mesh.model},
        {"top_surface_deviation",
         {{"mean", f->deviation_mean},
          {"p95", f->deviation_p95},
          {"max", f->deviation_max},
          {"samples", f->surface_samples},
          {"covered_samples", f->covered_samples},
          {"within_samples", f->within_samples},
          {"within_share", f->within_share},
          {"tolerance", o.tolerance},
          {"min_angle", o.min_angle},
          {"max_angle", o.max_angle}}},
        {"thickness_min", f->thickness_min},
        {"thickness_max", f->thickness_max},
        {"thickness_min_at",
         {f->thickness_min_at.x(), f->thickness_min_at.y(), f->thickness_min_at.z()}},
        {"thickness_max_at",
         {f->thickness_max_at.x(), f->thickness_max_at.y(), f->thickness_max_at.z()}},
        {"steepest_extrusion", f->steepest_deg},
        {"collisions", f->collisions},
        {"first_collision", f->collisions == 0
                                ? nlohmann::json(nullptr)
                                : nlohmann::json{{"line", f->first_collision_line},
                                                 {"at",
                                                  {f->first_collision.x(), f->first_collision.y(),
                                                   f->first_collision.z()}}}},
        {"volume_ratio", f->volume_ratio},
        {"outside_fraction", f->outside_fraction},
        {"extrusion_points", f->extrusions},
        {"print_time_s", seconds}};
    if (silent >= 0) j["print_time_silent_s"] = silent;
    std::printf("%s\n", j.dump(2).c_str());
    return kExitOk;
  }
  std::printf("%s against %s\n", o.gcode.c_str(), o.mesh.model.c_str());
  std::printf(
      "  top-surface deviation   mean %.4f  p95 %.4f  max %.4f mm  (%zu of %zu samples covered)\n",
      f->deviation_mean, f->deviation_p95, f->deviation_max, f->covered_samples,
      f->surface_samples);
  std::printf("  within %.3f mm          %.1f %% of the top's samples (facets %g-%g deg)\n",
              o.tolerance, 100 * f->within_share, o.min_angle, o.max_angle);
  std::printf(
      "  layer thickness         %.3f - %.3f mm  (thinnest at x %.2f y %.2f z %.2f, thickest "
      "at x %.2f y %.2f z %.2f)\n",
      f->thickness_min, f->thickness_max, f->thickness_min_at.x(), f->thickness_min_at.y(),
      f->thickness_min_at.z(), f->thickness_max_at.x(), f->thickness_max_at.y(),
      f->thickness_max_at.z());
  std::printf("  steepest extrusion      %.1f deg\n", f->steepest_deg);
  std::printf("  collisions              %zu", f->collisions);
  if (f->collisions > 0)
    std::printf("  (first at line %d, x %.2f y %.2f z %.2f)", f->first_collision_line,
                f->first_collision.x(), f->first_collision.y(), f->first_collision.z());
  std::printf("\n");
  std::printf("  extruded / mesh volume  %.3f\n", f->volume_ratio);
  std::printf("  extrusion outside mesh  %.2f %%\n", 100 * f->outside_fraction);
  std::printf("  print time (estimate)   %s", format_duration(seconds).c_str());
  if (silent >= 0) std::printf("  (silent mode %s)", format_duration(silent).c_str());
  std::printf("\n");
  return kExitOk;
}

}  // namespace

void register_check(CLI::App& app, std::function<int()>* run_fn) {
  auto o = std::make_shared<CheckOptions>();
  CLI::App* cmd = app.add_subcommand(
      "check",
      "Recompute the quality figures of a G-code file against its mesh (placed as PrusaSlicer\n"
      "places it: XY centre at the bed centre, lowest point at z = 0; in a file post-process\n"
      "wrote, where its header says the slicer put it): top-surface deviation,\n"
      "layer thickness, steepest extrusion, collisions, volume ratio, extrusion outside the\n"
      "mesh. Works on PrusaSlicer's G-code too, and reads the bed and printer from its\n"
      "settings block (the profile options go over it). See docs/check.md for each figure.");
  cmd->add_option("gcode", o->gcode, "G-code file")->required();
  cmd->add_option("--mesh", o->mesh.model, "The mesh it was sliced from")->required();
  o->profile.add_to(*cmd, "bed size, filament, layer height, the toolhead");
  cmd->add_option("--scale", o->mesh.load.scale, "Scale applied when slicing");
  cmd->add_option("--max-angle", o->max_angle, "Printable facet slope (deg)")
      ->capture_default_str();
  cmd->add_option("--min-angle", o->min_angle,
                  "Sample only facets at least this steep (deg): 2 leaves the flat tops out, "
                  "so the figures are the curved top's")
      ->capture_default_str();
  cmd->add_option("--tolerance", o->tolerance,
                  "The 'within' figure: share of the top's samples covered and at most this "
                  "far off (mm)")
      ->capture_default_str();
  // The head, as options too (kept from before the profile carried it).
  o->profile.add_keyed(*cmd, "--nozzle-tip-radius", "nozzle_tip_radius",
                       "mm (= --set nozzle_tip_radius=…)");
  o->profile.add_keyed(*cmd, "--block-radius", "heater_block_radius",
                       "mm (= --set heater_block_radius=…)");
  o->profile.add_keyed(*cmd, "--block-clearance", "heater_block_clearance",
                       "mm (= --set heater_block_clearance=…)");
  cmd->add_flag("--json", o->json, "Print one JSON document");
  cmd->add_flag("-q,--quiet", o->mesh.quiet, "No progress on stderr");
  *run_fn = nullptr;
  cmd->callback([o, run_fn] { *run_fn = [o] { return run(*o); }; });
}

}  // namespace nonplanar::cli
