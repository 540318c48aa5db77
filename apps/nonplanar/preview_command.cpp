// `nonplanar preview`: a G-code file as one self-contained HTML page (preview.hpp), with the
// mesh and what check finds marked when --mesh is given; `slice --preview` writes one too.
#include "preview_command.hpp"

#include <cstdio>
#include <filesystem>
#include <memory>

#include "cli_common.hpp"
#include "commands.hpp"
#include "core/atomic_file.hpp"
#include "core/file_bytes.hpp"
#include "nonplanar/check.hpp"
#include "nonplanar/gcode.hpp"
#include "nonplanar/pipeline.hpp"

namespace nonplanar::cli {

std::string preview_path_for(const std::string& gcode) {
  return std::filesystem::path(gcode).replace_extension(".html").string();
}

Expected<PreviewBuffers> write_preview(const PreviewInput& in, const PrintConfig& cfg,
                                       PreviewSummary summary) {
  const GcodeProgram program = read_gcode_program(in.gcode);
  PrintTime time;
  const PrintStats stats = print_stats(program, cfg, &time);
  PreviewParams params;
  params.filament_diameter = cfg.gcode.filament_diameter;
  PreviewBuffers buffers = preview_buffers(program, time.line_start, params);
  if (buffers.segments() == 0)
    return Error{Status::invalid_argument, in.name + ": no move to show"};
  summary.filament_g = stats.filament_g;
  if (summary.bed == std::array<double, 4>{0, 0, 0, 0})
    summary.bed = {cfg.bed_min.x(), cfg.bed_min.y(), cfg.bed_max.x(), cfg.bed_max.y()};
  if (summary.title.empty()) summary.title = std::filesystem::path(in.name).filename().string();
  const std::string page = preview_html(buffers, in.mesh, in.marks, summary);
  auto w = write_file_atomically(in.html, [&](std::ostream& os) {
    os.write(page.data(), static_cast<std::streamsize>(page.size()));
    return bool(os);
  });
  if (!w) return w.error();
  return buffers;
}

namespace {

struct PreviewOptions {
  MeshOptions mesh;
  ProfileOptions profile;
  std::string gcode, output, section, at;
  double max_angle = 30;
};

// --section: the beads crossing a vertical plane, as SVG, instead of the page.
int write_section(const PreviewOptions& o, std::string_view text, const PrintConfig& cfg,
                  const TriangleMesh* mesh) {
  auto at = parse_section_at(o.at);
  if (!at) return report_error(at.error());
  const GcodeProgram program = read_gcode_program(text);
  PreviewParams params;
  params.filament_diameter = cfg.gcode.filament_diameter;
  params.travels = false;
  auto svg = bead_section_svg(preview_buffers(program, {}, params), mesh, at->axis, at->value);
  if (!svg) return report_error({svg.error().status, o.gcode + ": " + svg.error().message});
  auto w = write_file_atomically(o.section, [&](std::ostream& os) {
    os.write(svg->data(), static_cast<std::streamsize>(svg->size()));
    return bool(os);
  });
  if (!w) return report_error(w.error());
  if (!o.mesh.quiet) std::fprintf(stderr, "wrote %s\n", o.section.c_str());
  return kExitOk;
}

// Where check's figures break the layer limits the slicer plans for (make_job's).
std::vector<Vec3> breaches(const CheckFigures& f, const PrintConfig& cfg, double max_angle) {
  const SliceJob job = make_job(cfg, max_angle);
  std::vector<Vec3> at;
  const double slack = job.gate.thickness_slack;  // what the slicer's own gate lets through
  if (f.thickness_min < job.layers.min_layer_height - slack) at.push_back(f.thickness_min_at);
  if (f.thickness_max > job.layers.max_layer_height + slack) at.push_back(f.thickness_max_at);
  return at;
}

int run(const PreviewOptions& o) {
  if (auto a = check_max_angle(o.max_angle); !a) return report_error(a.error());
  if (!o.section.empty() && !o.output.empty())
    return report_error(
        {Status::invalid_argument, "--section and -o: give one (a picture or a page)"});
  if (o.section.empty() && !o.at.empty())
    return report_error({Status::invalid_argument, "--at: goes with --section"});
  const std::string html = o.output.empty() ? preview_path_for(o.gcode) : o.output;
  const std::string out = o.section.empty() ? html : o.section;
  if (auto c = check_outputs({o.gcode, o.mesh.model}, {out}); !c) return report_error(c.error());
  auto bytes = core::read_file_bytes(o.gcode, 2ull << 30);
  if (!bytes) return report_error({bytes.error().status, o.gcode + ": " + bytes.error().message});
  auto cfg = o.profile.load(file_config(o.gcode, bytes->view(), o.mesh.quiet));
  if (!cfg) return report_error(cfg.error());
  Context ctx = make_context(o.mesh.quiet);
  PreviewInput in{o.gcode, bytes->view(), html, nullptr, {}};
  PreviewSummary summary;
  summary.max_angle_deg = o.max_angle;
  LoadedMesh loaded;
  if (!o.section.empty()) {
    if (!o.mesh.model.empty()) {
      auto m = load_mesh(o.mesh.model, o.mesh.placed_like(bytes->view(), *cfg, o.mesh.quiet), ctx);
      finish_progress();
      if (!m) return report_error(m.error());
      loaded = std::move(*m);
    }
    return write_section(o, bytes->view(), *cfg, o.mesh.model.empty() ? nullptr : &loaded.mesh);
  }
  if (!o.mesh.model.empty()) {
    // The figures check gives, from the same reading check makes (strict: what it cannot
    // read is an error here too).
    auto moves = read_gcode_moves(bytes->view());
    if (!moves) return report_error({moves.error().status, o.gcode + ": " + moves.error().message});
    auto m = load_mesh(o.mesh.model, o.mesh.placed_like(bytes->view(), *cfg, o.mesh.quiet), ctx);
    if (!m) return finish_progress(), report_error(m.error());
    loaded = std::move(*m);
    auto f = check_print(*moves, &loaded.mesh, check_params(*cfg, o.max_angle), ctx);
    if (!f)
      return finish_progress(),
             report_error({f.error().status, o.gcode + ": " + f.error().message});
    summary.p95 = f->extrusions > 0 ? f->deviation_p95 : -1;
    summary.collisions = static_cast<long long>(f->collisions);
    in.marks.collisions = f->collision_points;
    in.marks.breaches = breaches(*f, *cfg, o.max_angle);
    in.mesh = &loaded.mesh;
  }
  auto b = write_preview(in, *cfg, summary);
  finish_progress();
  if (!b) return report_error(b.error());
  if (!o.mesh.quiet) {
    std::fprintf(stderr, "wrote %s: %d layers (%d curved), %zu segments", html.c_str(), b->layers,
                 b->curved_layers, b->segments());
    if (summary.p95 >= 0)
      std::fprintf(stderr, ", top-surface p95 %.4f mm, %lld collisions", summary.p95,
                   summary.collisions);
    std::fprintf(stderr, "\n");
  }
  return kExitOk;
}

}  // namespace

void register_preview(CLI::App& app, std::function<int()>* run_fn) {
  auto o = std::make_shared<PreviewOptions>();
  CLI::App* cmd = app.add_subcommand(
      "preview",
      "Write a G-code file (ours, PrusaSlicer's or OrcaSlicer's) as one self-contained HTML\n"
      "page: its toolpaths in 3D (WebGL; orbit, pan, zoom), a slider over the file's own\n"
      "layers (;LAYER_CHANGE), colour by feature, layer thickness, slope, curved or planar\n"
      "layer and time. With --mesh, the mesh is drawn translucent (placed as check places\n"
      "it) and check's collisions and layer-limit breaches are marked where they are.");
  cmd->add_option("gcode", o->gcode, "G-code file")->required();
  cmd->add_option("--mesh", o->mesh.model, "The mesh it was sliced from (optional)");
  cmd->add_option("-o,--output", o->output, "HTML file to write (default: GCODE with .html)");
  cmd->add_option("--section", o->section,
                  "Instead of the page, an SVG picture of the beads crossing a vertical plane\n"
                  "(--at): curved layers orange, planar blue, the mesh's outline with --mesh");
  cmd->add_option("--at", o->at, "Where --section cuts: x=VALUE or y=VALUE (mm)");
  o->profile.add_to(*cmd, "bed, filament, layer limits, the toolhead (over the file's own)");
  cmd->add_option("--scale", o->mesh.load.scale, "Scale applied when slicing");
  cmd->add_option("--max-angle", o->max_angle, "Printable facet slope (deg)")
      ->capture_default_str();
  cmd->add_flag("-q,--quiet", o->mesh.quiet, "No progress or summary on stderr");
  *run_fn = nullptr;
  cmd->callback([o, run_fn] { *run_fn = [o] { return run(*o); }; });
}

}  // namespace nonplanar::cli
