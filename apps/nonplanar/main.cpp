// nonplanar: non-planar FDM slicing. This file only wires subcommands; the work is in the
// library (include/nonplanar, src/).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <functional>

#include "cli_common.hpp"
#include "commands.hpp"

int main(int argc, char** argv) {
  using namespace nonplanar::cli;
  forget_launcher_tunables();
  CLI::App app{
      "nonplanar - slice FDM parts with curved (non-planar) top layers.\n"
      "Run 'nonplanar COMMAND --help' for the options of a command."};
  app.set_version_flag("--version", "nonplanar 0.1.0");
  app.require_subcommand(1);
  app.fallthrough();  // the limits below may follow the command's own options
  Limits limits;
  add_limit_options(app, limits);
  std::function<int()> run;
  register_analyze(app, &run);
  register_fit(app, &run);
  register_layers(app, &run);
  register_slice(app, &run);
  register_check(app, &run);
  register_prepare(app, &run);
  register_post_process(app, &run);
  register_preview(app, &run);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? kExitOk : kExitBadInput;
  }
  install_interrupt_handler();
  if (!install_limits(limits)) return kExitBadInput;
  try {
    const int rc = run ? run() : kExitBadInput;
    // Figures that never reached their reader are not a success (`check --json > /dev/full`).
    if (!flush_stdout()) return rc == kExitOk ? kExitBadInput : rc;
    return rc;
  } catch (const std::bad_alloc&) {
    finish_progress();
    return report_out_of_memory();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: internal: %s\n", e.what());
  }
  return kExitFailure;
}
