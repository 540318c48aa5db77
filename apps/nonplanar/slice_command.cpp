// `nonplanar slice`: mesh → curved layers → toolpaths → G-code (the whole pipeline of
// DESIGN.md §2; --planar for flat layers only).
#include <cstdio>
#include <memory>

#include "cli_common.hpp"
#include "commands.hpp"
#include "nonplanar/gcode.hpp"
#include "nonplanar/pipeline.hpp"
#include "nonplanar/print_plan.hpp"
#include "nonplanar/unsupported_keys.hpp"
#include "preview_command.hpp"
#include "stage_timer.hpp"

namespace nonplanar::cli {
namespace {

// One line naming what the profile asks for and the built-in engine does not print.
void warn_unsupported(const PrintConfig& cfg) {
  const auto keys = unsupported_settings(cfg);
  if (keys.empty()) return;
  std::string list;
  for (const auto& k : keys) list += (list.empty() ? "" : ", ") + k;
  std::fprintf(stderr,
               "warning: the built-in engine does not print %s; they are left out "
               "(--engine prusaslicer prints them)\n",
               list.c_str());
}

struct SliceOptions {
  MeshOptions mesh;
  PresetOptions presets;
  std::string output;
  std::vector<std::string> config;  ///< profiles, each over the ones before
  std::string engine = "builtin", engine_path, engine_config, engine_filaments;
  bool planar = false, preview = false, timings = false;
  double max_angle = 30.0;
  // Overrides, applied by key after the profile, in this order.
  std::vector<std::pair<std::string, std::string*>> named;  // points into values
  std::vector<std::string> values;
  std::vector<std::string> sets;
};

int run(const SliceOptions& o) {
  PrintConfig cfg;
  EngineParams engine;
  if (o.engine == "prusaslicer")
    engine.engine = Engine::prusaslicer;
  else if (o.engine == "orcaslicer")
    engine.engine = Engine::orcaslicer;
  else if (o.engine != "builtin")
    return report_error({Status::invalid_argument,
                         "--engine: '" + o.engine + "' is not builtin, prusaslicer or orcaslicer"});
  engine.path = o.engine_path, engine.config = o.engine_config,
  engine.filaments = o.engine_filaments;
  // PrusaSlicer's profile is ours too (layer heights, bed, filament), unless --config names
  // one. Several --config files load in order, each over the ones before.
  std::vector<std::pair<std::string, std::string>> preset_keys;
  if (auto p = o.presets.apply(cfg, &preset_keys); !p) return report_error(p.error());
  // The engine gets the presets as keys, before the user's own overrides.
  for (auto& [k, v] : preset_keys)
    if (!is_nonplanar_key(k)) engine.overrides.emplace_back(std::move(k), std::move(v));
  std::vector<std::string> profiles = o.config;
  if (profiles.empty() && engine.engine == Engine::prusaslicer && !o.engine_config.empty())
    profiles.push_back(o.engine_config);
  for (const std::string& profile : profiles) {
    auto c = load_config(profile, std::move(cfg));
    if (!c) return report_error(c.error());
    cfg = std::move(*c);
  }
  // Overrides in order: the named options, then --set. The engine gets its own keys only.
  std::vector<std::string> overrides;
  for (const auto& [key, value] : o.named)
    if (!value->empty()) overrides.push_back(key + "=" + *value);
  overrides.insert(overrides.end(), o.sets.begin(), o.sets.end());
  std::vector<std::string> engine_only;
  for (const std::string& kv : overrides) {
    // A key only the engine knows (brim_width, support_material, ...) goes to it alone.
    auto applied = apply_setting(cfg, kv, engine.engine != Engine::builtin);
    if (!applied) return report_error(applied.error());
    if (!applied->known && engine.engine != Engine::builtin) engine_only.push_back(applied->key);
    if (!is_nonplanar_key(applied->key))
      engine.overrides.emplace_back(std::move(applied->key), std::move(applied->value));
  }
  if (auto v = validate_config(cfg); !v) return report_error(v.error());
  if (auto a = check_max_angle(o.max_angle); !a) return report_error(a.error());
  // The file -o names: known once the profile is (its name macros read the profile).
  const auto output = output_path(o.output, o.mesh.model, cfg);
  if (!output) return report_error(output.error());
  std::vector<std::string> inputs = o.config;
  inputs.insert(inputs.end(), {o.mesh.model, o.engine_config, o.engine_filaments, o.engine_path});
  const std::string preview = o.preview ? preview_path_for(*output) : std::string();
  if (auto c = check_outputs(inputs, {*output, preview}); !c) return report_error(c.error());
  if (!o.mesh.quiet) {
    // What the built-in engine substitutes (a fill pattern it lacks) and leaves out: another
    // engine does both itself.
    if (engine.engine == Engine::builtin) {
      for (const auto& n : cfg.notes) std::fprintf(stderr, "warning: %s\n", n.c_str());
      warn_unsupported(cfg);
    }
    for (const auto& k : engine_only)
      std::fprintf(stderr,
                   "notice: %s is passed to %s only (the built-in engine has no such "
                   "setting)\n",
                   k.c_str(), o.engine.c_str());
  }

  Context ctx = make_context(o.mesh.quiet);
  StageTimer timer;
  if (o.timings) timer.attach(ctx);
  LoadParams lp = o.mesh.load;
  lp.bed_center = cfg.bed_center();
  auto loaded = load_mesh(o.mesh.model, lp, ctx);
  if (!loaded) return finish_progress(), report_error(loaded.error());
  const BoundingBox box = bounding_box(loaded->mesh);
  const Vec2 bed = cfg.bed_max - cfg.bed_min;
  if (box.size().x() > bed.x() + 1e-6 || box.size().y() > bed.y() + 1e-6) {
    char buf[160];
    std::snprintf(buf, sizeof buf, ": part is %.1f x %.1f mm, larger than the bed (%.1f x %.1f mm)",
                  box.size().x(), box.size().y(), bed.x(), bed.y());
    return finish_progress(), report_error({Status::invalid_argument, o.mesh.model + buf});
  }
  cfg.gcode.object_name = std::filesystem::path(o.mesh.model).filename().string();
  SliceJob job = make_job(cfg, o.max_angle);
  job.planar_only = o.planar;
  job.engine = engine;
  job.keep_paths = false;  // the file is written from the text
  job.header.push_back("model: " + o.mesh.model);
  {  // where check and preview find the part, whatever printer the file was sliced for
    char buf[120];
    std::snprintf(buf, sizeof buf, "%.3f, %.3f mm on the bed", 0.5 * (box.min.x() + box.max.x()),
                  0.5 * (box.min.y() + box.max.y()));
    job.header.push_back(std::string(kPartCentredAt.substr(2)) + buf);
  }
  if (loaded->objects.several()) {
    // A 3MF's build items, where it placed them: each layer prints them one by one, each
    // with its own label. Another slicer gets the normalised part as one object, and so does
    // a plate of more objects than the library prints apart.
    if (job.engine.engine == Engine::builtin)
      job.objects = object_outlines(loaded->mesh, loaded->objects);
    const std::size_t n = loaded->objects.items.size();
    if (!job.objects.empty()) {
      cfg.gcode.objects = job.print.gcode.objects = loaded->objects.items;
    } else if (!o.mesh.quiet) {
      const std::string why = job.engine.engine != Engine::builtin ? " through " + o.engine
                              : n > kMostPlateObjects
                                  ? " (more than " + std::to_string(kMostPlateObjects) + ")"
                                  : "";
      std::fprintf(stderr, "notice: %s: its %zu objects print as one object%s\n",
                   o.mesh.model.c_str(), n, why.c_str());
    }
  }
  auto result = slice_model(loaded->mesh, job, ctx);
  if (!result) {
    Error e = result.error();
    if (e.status == Status::invalid_mesh) e.message = o.mesh.model + ": " + e.message;
    return finish_progress(), report_error(e);
  }
  timer.mark("write");
  auto w = write_gcode_text(*output, result->gcode, ctx);
  if (w && o.preview) {
    timer.mark("preview");
    // The gate found 0 collisions; the page has the placed mesh and the file's own layers.
    PreviewSummary summary;
    summary.collisions = 0;
    summary.max_angle_deg = job.analysis.max_angle_deg;
    PreviewInput in{*output, result->gcode, preview, &loaded->mesh, {}};
    if (auto p = write_preview(in, cfg, summary); !p) w = p.error();
  }
  finish_progress();
  if (!w) return report_error(w.error());
  if (o.timings) timer.print(stderr);
  report_warnings(o.mesh.model, *loaded, o.mesh.quiet);
  if (!o.mesh.quiet) {
    for (const auto& n : result->notices)
      if (n.kind != Notice::Kind::summary) std::fprintf(stderr, "notice: %s\n", n.text.c_str());
    char curved[80];
    if (result->shell_layers > 0)
      std::snprintf(curved, sizeof curved, "a curved shell of %d layers", result->shell_layers);
    else
      std::snprintf(curved, sizeof curved, "%zu curved stack%s", result->plan.stacks.size(),
                    result->plan.stacks.size() == 1 ? "" : "s");
    std::fprintf(stderr,
                 "wrote %s: %zu layers, %s, layer thickness %.3f-%.3f mm, "
                 "steepest extrusion %.1f deg, 0 collisions, %s, %.2f m of filament\n",
                 output->c_str(), result->layers.size(), curved, result->thickness_min,
                 result->thickness_max, result->steepest_deg,
                 format_duration(result->stats.seconds).c_str(),
                 result->stats.filament_mm / 1000.0);
    if (o.preview) std::fprintf(stderr, "wrote %s (open it in a browser)\n", preview.c_str());
    for (const auto& n : result->notices)  // the last word, after what was written
      if (n.kind == Notice::Kind::summary) std::fprintf(stderr, "%s\n", n.text.c_str());
  }
  return kExitOk;
}

}  // namespace

void register_slice(CLI::App& app, std::function<int()>* run_fn) {
  auto o = std::make_shared<SliceOptions>();
  CLI::App* cmd = app.add_subcommand(
      "slice",
      "Slice a model into G-code with curved top layers where the surface allows (see\n"
      "'layers'), planar elsewhere; --planar slices flat only. Defaults print on a generic\n"
      "0.4 mm nozzle Marlin 2 printer\n"
      "with a 220 x 220 mm bed; --config loads a JSON profile or a PrusaSlicer .ini, and\n"
      "the options below (or --set KEY=VALUE with any PrusaSlicer key) override it.");
  o->mesh.add_to(*cmd);
  cmd->add_option("-o,--output", o->output,
                  "G-code file to write (atomically); a folder gets MODEL.gcode in it, and "
                  "PrusaSlicer's name macros are expanded ([input_filename_base], {layer_height})")
      ->required();
  o->presets.add_to(*cmd);
  cmd->add_option("--load,--config", o->config,
                  "Profile: PrusaSlicer .ini, OrcaSlicer machine/process/filament .json (its\n"
                  "inherits resolved; docs/orcaslicer-profiles.md) or a flat .json; repeat it for\n"
                  "a printer, a print and a filament file, each over the ones before");
  cmd->add_flag("--planar", o->planar, "Planar layers only (the ordinary slicing engine)");
  cmd->add_flag(
      "--timings", o->timings,
      "Print the wall and CPU time of each stage (load, analyze, fit, layers, normalize, "
      "slice, toolpaths or engine, map back, gate, gcode, collisions, stats, write), a retry's "
      "stages again in order, on stderr; 'cores' below 2 shows a core left idle, 'rss MB' "
      "the memory in use when the stage ends, 'peak MB' the run's peak so far");
  cmd->add_flag("--preview", o->preview,
                "Also write OUTPUT.html: the toolpaths in 3D with a slider over the layers "
                "(see 'preview')");
  cmd->add_option("--engine", o->engine,
                  "Planar engine for the normalised mesh: builtin, prusaslicer (PrusaSlicer 2.5+\n"
                  "command line; a shell over a planar core: one run, split and stitched) or\n"
                  "orcaslicer (untested; no shells); its G-code is mapped back")
      ->capture_default_str();
  cmd->add_option("--engine-path", o->engine_path,
                  "The engine's executable (default: prusa-slicer / orca-slicer on PATH)");
  cmd->add_option("--engine-config", o->engine_config,
                  "The engine's profile: a PrusaSlicer .ini (also read as --config when that is\n"
                  "not given), or OrcaSlicer's --load-settings \"machine.json;process.json\"");
  cmd->add_option("--engine-filaments", o->engine_filaments, "OrcaSlicer's --load-filaments");
  cmd->add_option("--max-angle", o->max_angle,
                  "Steepest surface printed non-planar, degrees (nozzle geometry)")
      ->capture_default_str();
  static const char* keys[][2] = {
      {"layer_height", "Layer height (mm)"},
      {"first_layer_height", "First layer height (mm or %)"},
      {"min_layer_height", "Thinnest curved layer, h_min (mm; 0 = automatic)"},
      {"max_layer_height", "Thickest curved layer, h_max (mm; 0 = automatic)"},
      {"fill_density", "Sparse infill density (0.2 or 20%)"},
      {"fill_pattern", "rectilinear or grid"},
      {"perimeters", "Perimeter loops"},
      {"top_solid_layers", "Solid layers under top surfaces"},
      {"bottom_solid_layers", "Solid layers over bottom surfaces"},
      {"shell_layers",
       "Curved layers of a shell over a planar core (0 = automatic: 0.4 mm,\n"
       "at least 2; more print slower, the core's solid layers under them)"},
      {"shell_max_banded",
       "Largest share of a shell printed in bands beside taller parts\n"
       "(0 to 1, default 1; bands cost print time, past it planar)"},
      {"temperature", "Nozzle temperature (C)"},
      {"bed_temperature", "Bed temperature (C)"},
      {"nozzle_diameter", "Nozzle diameter (mm)"},
      {"filament_diameter", "Filament diameter (mm)"},
      {"extrusion_width", "Extrusion width (mm, % of layer height, 0 = 1.125 x nozzle)"},
      {"retract_length", "Retraction length (mm)"},
      {"retract_lift", "Z-hop on retraction (mm)"},
      {"skirts", "Skirt loops"},
      {"gcode_flavor", "marlin2, klipper or reprapfirmware"},
      {"use_relative_e_distances", "1 for relative E (M83)"},
  };
  o->values.resize(std::size(keys));  // sized once: named keeps pointers into it
  for (std::size_t i = 0; i < std::size(keys); ++i) {
    std::string flag = std::string("--") + keys[i][0];
    for (char& ch : flag)
      if (ch == '_') ch = '-';
    if (flag == "--use-relative-e-distances") flag = "--relative-e";
    cmd->add_option(flag, o->values[i], keys[i][1]);
    o->named.emplace_back(keys[i][0], &o->values[i]);
  }
  cmd->add_option("--set", o->sets,
                  "Any setting by its key: --set KEY=VALUE (PrusaSlicer's keys, and the\n"
                  "toolhead's: nozzle_cone_angle, toolhead_shape, ...; docs/toolhead.md)");
  *run_fn = nullptr;
  cmd->callback([o, run_fn] { *run_fn = [o] { return run(*o); }; });
}

}  // namespace nonplanar::cli
