// Subcommands of the nonplanar CLI; each registers its options and returns an exit code.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace nonplanar::cli {

/// Adds "analyze" to app; *run is set to the function main calls when it is chosen.
void register_analyze(CLI::App& app, std::function<int()>* run);
/// Adds "fit".
void register_fit(CLI::App& app, std::function<int()>* run);
/// Adds "layers".
void register_layers(CLI::App& app, std::function<int()>* run);
/// Adds "slice".
void register_slice(CLI::App& app, std::function<int()>* run);
/// Adds "check".
void register_check(CLI::App& app, std::function<int()>* run);
/// Adds "prepare".
void register_prepare(CLI::App& app, std::function<int()>* run);
/// Adds "post-process".
void register_post_process(CLI::App& app, std::function<int()>* run);
/// Adds "preview".
void register_preview(CLI::App& app, std::function<int()>* run);

}  // namespace nonplanar::cli
