#include "cli_common.hpp"

#include <unistd.h>

#include <cstdio>

namespace nonplanar::cli {
namespace {
bool g_progress_drawn = false;
}

void MeshOptions::add_to(CLI::App& cmd) {
  cmd.add_option("model", model, "Mesh file: .stl (binary or ASCII), .obj, .off or .3mf")
      ->required();
  cmd.add_option("--scale", load.scale, "Uniform scale factor applied to the model")
      ->capture_default_str();
  cmd.add_option("--rotate-x", load.rotate_x_deg, "Rotate about X (degrees), before Y and Z");
  cmd.add_option("--rotate-y", load.rotate_y_deg, "Rotate about Y (degrees)");
  cmd.add_option("--rotate-z", load.rotate_z_deg, "Rotate about Z (degrees)");
  cmd.add_flag("-q,--quiet", quiet, "No progress or warnings on stderr");
}

void add_analysis_options(CLI::App& cmd, AnalysisParams& p) {
  cmd.add_option("--max-angle", p.max_angle_deg,
                 "Steepest printable face, degrees from horizontal (nozzle geometry)")
      ->capture_default_str();
  cmd.add_option("--tau", p.tau, "Curvature threshold K/A for a discontinuous vertex (1/mm^2)")
      ->capture_default_str();
  cmd.add_option("--epsilon", p.epsilon,
                 "Largest curvature jump between neighbouring vertices (1/mm^2)")
      ->capture_default_str();
  cmd.add_option("--crease-angle", p.crease_angle_deg,
                 "Dihedral angle between faces that splits a patch (degrees)")
      ->capture_default_str();
  cmd.add_option("--min-layer-height", p.min_layer_height,
                 "A patch whose height range is below this is flat (mm)")
      ->capture_default_str();
  cmd.add_option("--min-patch-area", p.min_patch_area, "Smaller patches are dropped (mm^2)")
      ->capture_default_str();
}

int report_error(const Error& e) {
  std::fprintf(stderr, "error: %s\n", e.message.c_str());
  switch (e.status) {
    case Status::invalid_argument:
    case Status::io_error:
    case Status::parse_error:
    case Status::invalid_mesh:
    case Status::unsupported:
      return kExitBadInput;
    default:
      return kExitFailure;
  }
}

void report_warnings(const std::string& file, const LoadedMesh& m, bool quiet) {
  if (quiet) return;
  for (const auto& w : m.warnings)
    std::fprintf(stderr, "warning: %s: %s\n", file.c_str(), w.c_str());
}

Context make_context(bool quiet) {
  Context ctx;
  if (!quiet && ::isatty(STDERR_FILENO)) {
    ctx.on_progress = [](std::string_view stage, double f) {
      std::fprintf(stderr, "\r%-10.*s %3d%%", static_cast<int>(stage.size()), stage.data(),
                   static_cast<int>(f * 100.0 + 0.5));
      std::fflush(stderr);
      g_progress_drawn = true;
    };
  }
  return ctx;
}

void finish_progress() {
  if (g_progress_drawn) std::fprintf(stderr, "\r%20s\r", "");
  g_progress_drawn = false;
}

}  // namespace nonplanar::cli
