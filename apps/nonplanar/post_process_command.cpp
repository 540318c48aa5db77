// `nonplanar post-process`: the post-processing script of PrusaSlicer, OrcaSlicer and Bambu
// Studio. It maps the G-code of a part `prepare` wrote back onto the curved layers, in place.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include "cli_common.hpp"
#include "commands.hpp"
#include "core/file_bytes.hpp"
#include "nonplanar/gcode.hpp"
#include "nonplanar/print_plan.hpp"
#include "nonplanar/print_time.hpp"

namespace nonplanar::cli {
namespace {

namespace fs = std::filesystem;

constexpr const char* kPlanPart = "Metadata/nonplanar_plan.json";

struct PostProcessOptions {
  std::string gcode, plan, output;
  bool quiet = false;
};

// A plan from a 3MF prepare wrote, or from the plan's JSON file itself.
Expected<PrintPlan> load_plan(const fs::path& file) {
  std::string text;
  if (file.extension() == ".3mf") {
    auto part = read_3mf_part(file, kPlanPart);
    if (!part) return part.error();
    text = std::move(*part);
  } else {
    auto bytes = core::read_file_bytes(file, std::size_t(1) << 30);
    if (!bytes) return Error{bytes.error().status, file.string() + ": " + bytes.error().message};
    text = std::string(bytes->view());
  }
  auto plan = parse_plan_json(text);
  if (!plan) return Error{plan.error().status, file.string() + ": " + plan.error().message};
  return plan;
}

// The file's name without the slicer's temporary suffix (PrusaSlicer passes NAME.gcode.pp).
fs::path final_name(const std::string& gcode) {
  if (const char* out = std::getenv("SLIC3R_PP_OUTPUT_NAME"); out && *out) return out;
  fs::path p(gcode);
  if (p.extension() == ".pp") p.replace_extension();
  return p;
}

// --plan, else a 3MF named after an object label of the file, or after the file itself, beside
// the final G-code or the file given. With labels, the plan's object must be one of them.
Expected<PrintPlan> find_plan(const PostProcessOptions& o, std::string_view gcode) {
  if (!o.plan.empty()) return load_plan(o.plan);
  const auto labels = gcode_object_names(gcode);
  std::vector<fs::path> dirs{final_name(o.gcode).parent_path(), fs::path(o.gcode).parent_path()};
  std::vector<std::string> stems = labels;
  stems.push_back(final_name(o.gcode).stem().string());
  std::string looked;
  for (const fs::path& dir : dirs)
    for (const std::string& stem : stems) {
      const fs::path f = (dir.empty() ? fs::path(".") : dir) / (stem + ".3mf");
      if (looked.find(f.string()) != std::string::npos) continue;
      looked += (looked.empty() ? "" : ", ") + f.string();
      std::error_code ec;
      if (!fs::is_regular_file(f, ec)) continue;
      auto plan = load_plan(f);
      if (!plan) continue;
      if (labels.empty() || std::find(labels.begin(), labels.end(), plan->object) != labels.end())
        return plan;
    }
  // Labels name the object, not the 3MF: any 3MF beside it holding that object's plan.
  for (const fs::path& dir : dirs) {
    std::error_code ec;
    int seen = 0;
    for (auto it = fs::directory_iterator(dir.empty() ? fs::path(".") : dir, ec);
         !labels.empty() && !ec && it != fs::directory_iterator() && seen < 200;
         it.increment(ec), ++seen) {
      if (it->path().extension() != ".3mf" || !it->is_regular_file(ec)) continue;
      auto plan = load_plan(it->path());
      if (plan && std::find(labels.begin(), labels.end(), plan->object) != labels.end())
        return plan;
    }
  }
  return Error{Status::invalid_argument,
               "no plan found (looked for " + looked +
                   (labels.empty() ? "" : " and any 3MF there of " + labels[0]) +
                   "): give the 3MF that 'nonplanar prepare' wrote with --plan FILE.3mf"};
}

int run(const PostProcessOptions& o) {
  const std::string out = o.output.empty() ? o.gcode : o.output;
  if (!o.output.empty())
    if (auto c = check_outputs({o.gcode, o.plan}, {out}); !c) return report_error(c.error());
  auto bytes = core::read_file_bytes(o.gcode, std::size_t(2) << 30);
  if (!bytes) return report_error({bytes.error().status, o.gcode + ": " + bytes.error().message});
  auto plan = find_plan(o, bytes->view());
  if (!plan) return report_error({plan.error().status, o.gcode + ": " + plan.error().message});
  Context ctx = make_context(o.quiet);
  auto mapped = post_process_gcode(bytes->view(), *plan, ctx);
  finish_progress();
  if (!mapped) {
    Error e = mapped.error();
    if (e.status == Status::internal_error) e.status = Status::invalid_argument;
    e.message = o.gcode + ": " + e.message;
    return report_error(e);
  }
  if (auto w = write_gcode_text(out, mapped->gcode, ctx); !w) return report_error(w.error());
  for (const std::string& n : mapped->notices)
    if (!o.quiet) std::fprintf(stderr, "notice: %s\n", n.c_str());
  if (!o.quiet)
    std::fprintf(stderr,
                 "mapped %s onto the curved layers of %s: %zu layers, layer thickness "
                 "%.3f-%.3f mm, steepest extrusion %.1f deg, 0 collisions, %s, %.2f m of "
                 "filament\n",
                 final_name(o.gcode).filename().c_str(), plan->object.c_str(), mapped->layers,
                 mapped->thickness_min, mapped->thickness_max, mapped->steepest_deg,
                 format_duration(mapped->stats.seconds).c_str(),
                 mapped->stats.filament_mm / 1000.0);
  return kExitOk;
}

}  // namespace

void register_post_process(CLI::App& app, std::function<int()>* run_fn) {
  auto o = std::make_shared<PostProcessOptions>();
  CLI::App* cmd = app.add_subcommand(
      "post-process",
      "Map the G-code your slicer made of a part 'nonplanar prepare' wrote back onto its\n"
      "curved layers, in place: paste it into PrusaSlicer's, OrcaSlicer's or Bambu Studio's\n"
      "post-processing scripts. The plan is the prepared 3MF (--plan), else a 3MF beside the\n"
      "G-code named after its object labels or after the G-code. Refused with one line and\n"
      "the file untouched when the slicer changed what the plan needs (layer heights, arcs,\n"
      "scale or rotation). Other objects on the plate (told apart by the slicer's object\n"
      "labels) stay as the slicer wrote them; a curved shell prints after them.");
  cmd->add_option("gcode", o->gcode, "The G-code file (the slicer passes it)")->required();
  cmd->add_option("--plan", o->plan, "The 3MF 'nonplanar prepare' wrote (or its plan JSON)");
  cmd->add_option("-o,--output", o->output, "Write here instead of in place (atomically)");
  cmd->add_flag("-q,--quiet", o->quiet, "No summary line");
  *run_fn = nullptr;
  cmd->callback([o, run_fn] { *run_fn = [o] { return run(*o); }; });
}

}  // namespace nonplanar::cli
