// `nonplanar prepare`: plan the curved layers and write the normalised part as a 3MF, with
// the plan inside it, for the user's own slicer; its post-processing script
// (`nonplanar post-process`) maps the G-code back.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "cli_common.hpp"
#include "commands.hpp"
#include "nonplanar/config.hpp"
#include "nonplanar/print_plan.hpp"
#include "nonplanar/print_time.hpp"

namespace nonplanar::cli {
namespace {

namespace fs = std::filesystem;

struct PrepareOptions {
  MeshOptions mesh;
  ProfileOptions profile;
  std::string output, check_with = "builtin", engine_path;
  double max_angle = 30.0;
};

// What checks the plan: the built-in engine, or PrusaSlicer with the same profile (its paths
// are the ones the user's slicer will make; a patch they would push past a limit is then
// left planar here rather than refused by post-process later).
Expected<EngineParams> checker(const PrepareOptions& o) {
  EngineParams e;
  if (o.check_with == "builtin") return e;
  if (o.check_with != "prusaslicer")
    return Error{Status::invalid_argument,
                 "--check-with: '" + o.check_with + "' is not builtin or prusaslicer"};
  if (o.profile.config.size() > 1)
    return Error{Status::invalid_argument,
                 "--check-with prusaslicer takes one --config file (PrusaSlicer loads one)"};
  e.engine = Engine::prusaslicer, e.path = o.engine_path;
  if (!o.profile.config.empty()) e.config = o.profile.config[0];
  PrintConfig scratch;
  if (auto p = o.profile.presets.apply(scratch, &e.overrides); !p) return p.error();
  std::vector<std::string> sets;
  for (const auto& [key, value] : o.profile.keyed)
    if (!value.empty()) sets.push_back(key + "=" + value);
  sets.insert(sets.end(), o.profile.sets.begin(), o.profile.sets.end());
  for (const std::string& kv : sets) {
    auto applied = apply_setting(scratch, kv);
    if (!applied) return applied.error();
    if (!is_nonplanar_key(applied->key)) e.overrides.emplace_back(applied->key, applied->value);
  }
  return e;
}

// Where -o points: a folder (existing, or ending in '/') gets MODEL.3mf.
std::string output_file(const PrepareOptions& o) {
  const fs::path out(o.output);
  if (fs::is_directory(out) || (!o.output.empty() && o.output.back() == '/'))
    return (out / fs::path(o.mesh.model).stem()).string() + ".3mf";
  return o.output;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

// The absolute path of the command, for the line to paste into the slicer: the launcher
// beside this program (apps/launcher), which is what a user runs.
std::string self_path() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return "nonplanar";
  const fs::path launcher = p.parent_path() / "nonplanar";
  return p.filename() == "nonplanar-core" && fs::exists(launcher, ec) ? launcher.string()
                                                                      : p.string();
}

std::string quoted(const std::string& s) {
  if (s.find_first_of(" '\"\\$`") == std::string::npos) return s;
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

void print_instructions(const std::string& out, const PreparedPart& part) {
  const PrintPlan& p = part.plan;
  if (part.shell_layers > 0)
    std::fprintf(stderr,
                 "wrote %s: %s, a curved shell of %d layers over a planar core (the shell's "
                 "layers stand above the part in the 3MF until post-process lays them on it)\n",
                 out.c_str(), p.object.c_str(), part.shell_layers);
  else
    std::fprintf(stderr, "wrote %s: %s, %zu curved stack%s\n", out.c_str(), p.object.c_str(),
                 part.stacks, part.stacks == 1 ? "" : "s");
  std::fprintf(stderr,
               "In PrusaSlicer or OrcaSlicer, open it with your own printer and filament, and "
               "keep:\n");
  if (part.shell_layers > 0)
    std::fprintf(stderr,
                 "  - the object's variable layer height as prepared (do not edit or reset it) "
                 "and first layer height %s mm; arc fitting off; no scaling or rotating "
                 "(moving is fine); other objects on the plate only with Label objects on, "
                 "and none taller than the shell near it (the shell prints after them);\n",
                 num(p.first_layer_height).c_str());
  else
    std::fprintf(stderr,
                 "  - layer height %s mm (set on the object) and first layer height %s mm;\n"
                 "  - variable layer height and arc fitting off; no scaling or rotating (moving "
                 "is fine);\n",
                 num(p.layer_height).c_str(), num(p.first_layer_height).c_str());
  std::fprintf(stderr,
               "  - this post-processing script (Print Settings > Output options):\n"
               "      %s post-process --plan %s\n",
               quoted(self_path()).c_str(), quoted(fs::absolute(out).string()).c_str());
}

int run(const PrepareOptions& o) {
  auto cfg = o.profile.load();
  if (!cfg) return report_error(cfg.error());
  if (auto a = check_max_angle(o.max_angle); !a) return report_error(a.error());
  const std::string out = output_file(o);
  if (fs::path(out).extension() != ".3mf")
    return report_error({Status::invalid_argument, "-o " + out + ": prepare writes a .3mf"});
  std::vector<std::string> inputs = o.profile.config;
  inputs.push_back(o.mesh.model);
  if (auto c = check_outputs(inputs, {out}); !c) return report_error(c.error());
  auto engine = checker(o);
  if (!engine) return report_error(engine.error());
  SliceJob job = make_job(*cfg, o.max_angle);
  job.engine = *engine;
  if (!o.mesh.quiet)
    for (const Notice& n : job.notices) std::fprintf(stderr, "notice: %s\n", n.text.c_str());
  Context ctx = make_context(o.mesh.quiet);
  LoadParams lp = o.mesh.load;
  lp.bed_center = cfg->bed_center();
  auto loaded = load_mesh(o.mesh.model, lp, ctx);
  if (!loaded) return finish_progress(), report_error(loaded.error());
  if (loaded->objects.several() && !o.mesh.quiet)
    std::fprintf(stderr, "notice: %s: its %zu objects are prepared as one object\n",
                 o.mesh.model.c_str(), loaded->objects.items.size());
  job.header.push_back("model: " + o.mesh.model);
  auto part = prepare_part(loaded->mesh, job, ctx);
  if (!part) {
    finish_progress();
    Error e = part.error();
    if (e.status == Status::unsupported || e.status == Status::invalid_mesh)
      e = {Status::invalid_argument, o.mesh.model + ": " + e.message};
    return report_error(e);
  }
  part->plan.object = fs::path(o.mesh.model).stem().string();
  part->plan.model = fs::path(o.mesh.model).filename().string();
  Object3mf object{part->plan.object, {{"layer_height", num(part->plan.layer_height)}}, {}};
  if (!part->support_blocker.faces.empty())
    object.support_blockers.push_back(part->support_blocker);
  std::vector<PackageFile> files{{"/Metadata/nonplanar_plan.json", plan_json(part->plan)}};
  // A shell's core layers: PrusaSlicer's profile, and the same under the name OrcaSlicer and
  // Bambu Studio read (their 3MF's Metadata/layer_heights_profile.txt; untested here).
  if (!part->layer_heights_profile.empty())
    files.insert(files.end(),
                 {{"/Metadata/Slic3r_PE_layer_heights_profile.txt", part->layer_heights_profile},
                  {"/Metadata/layer_heights_profile.txt", part->layer_heights_profile}});
  auto w = write_3mf(out, part->normalized, files, object);
  finish_progress();
  if (!w) return report_error(w.error());
  report_warnings(o.mesh.model, *loaded, o.mesh.quiet);
  if (!o.mesh.quiet) {
    for (const Notice& n : part->notices)
      if (n.kind != Notice::Kind::summary) std::fprintf(stderr, "notice: %s\n", n.text.c_str());
    print_instructions(out, *part);
  }
  return kExitOk;
}

}  // namespace

void register_prepare(CLI::App& app, std::function<int()>* run_fn) {
  auto o = std::make_shared<PrepareOptions>();
  CLI::App* cmd = app.add_subcommand(
      "prepare",
      "Plan the curved layers of a model for your own slicer: write the normalised part as a\n"
      "3MF (the plan inside it) to slice in PrusaSlicer or OrcaSlicer with your profile; its\n"
      "post-processing script, 'nonplanar post-process', maps the G-code back. Give the\n"
      "profile you will slice with (--config or presets): the plan is made for its layers.\n"
      "A top no stack fits prints as a curved shell over a planar core: the 3MF then holds\n"
      "the part with the shell's layers above it, on its own layer-height profile.");
  o->mesh.add_to(*cmd);
  cmd->add_option("-o,--output", o->output,
                  "3MF file to write (atomically); a folder gets MODEL.3mf")
      ->required();
  o->profile.add_to(*cmd, "the printer, print and filament you will slice with");
  o->profile.add_keyed(*cmd, "--layer-height", "layer_height", "Layer height (mm)");
  o->profile.add_keyed(*cmd, "--first-layer-height", "first_layer_height",
                       "First layer height (mm or %)");
  o->profile.add_keyed(*cmd, "--min-layer-height", "min_layer_height",
                       "Thinnest curved layer, h_min (mm; 0 = automatic)");
  o->profile.add_keyed(*cmd, "--max-layer-height", "max_layer_height",
                       "Thickest curved layer, h_max (mm; 0 = automatic)");
  cmd->add_option("--max-angle", o->max_angle,
                  "Steepest surface printed non-planar, degrees (nozzle geometry)")
      ->capture_default_str();
  cmd->add_option("--check-with", o->check_with,
                  "What slices the plan to check it: builtin, or prusaslicer (the profile's own\n"
                  "paths: a patch they would push past a limit stays planar here, instead of\n"
                  "post-process refusing the file)")
      ->capture_default_str();
  cmd->add_option("--engine-path", o->engine_path,
                  "PrusaSlicer's executable for --check-with (default: prusa-slicer on PATH)");
  *run_fn = nullptr;
  cmd->callback([o, run_fn] { *run_fn = [o] { return run(*o); }; });
}

}  // namespace nonplanar::cli
