// Pieces every nonplanar subcommand shares: mesh-loading options, error reporting,
// progress on stderr.
#pragma once

#include <CLI/CLI.hpp>
#include <list>
#include <string>
#include <utility>
#include <vector>

#include "nonplanar/analysis.hpp"
#include "nonplanar/config.hpp"
#include "nonplanar/context.hpp"
#include "nonplanar/io.hpp"
#include "nonplanar/presets.hpp"
#include "nonplanar/status.hpp"

namespace nonplanar::cli {

/// Exit codes: 0 success, 2 bad input or arguments, 1 anything else (an internal failure).
constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitInterrupted = 130;  ///< 128 + SIGINT, as shells report it

/// Ctrl-C / SIGTERM raise the flag every make_context() Context carries; a second one exits
/// at once after removing any half-written temporary file. Call once from main.
void install_interrupt_handler();

/// Resource limits for one run (README, "Faults"): 0 means none.
struct Limits {
  double max_memory_mb = 0;  ///< address space, enforced with RLIMIT_AS
  double max_time_s = 0;     ///< wall time; then the run stops as on Ctrl-C, with exit 2
};
/// --max-memory and --max-time on the top-level app (they work after the command too).
void add_limit_options(CLI::App& app, Limits& l);
/// Applies the limits; false (after an error line) if the system refused.
bool install_limits(const Limits& l);
/// The message and exit code for std::bad_alloc: exit 2 under --max-memory, else 1.
int report_out_of_memory();

/// Options for reading and placing the model, added to a subcommand.
struct MeshOptions {
  std::string model;
  LoadParams load;
  bool quiet = false;
  void add_to(CLI::App& cmd);
  /// How to load the mesh a G-code file was sliced from, placed where that file has it: the
  /// centre its header gives (post_processed_centre: files post-process or slice wrote), else
  /// the bed centre of `cfg`. Says so on stderr (unless `quiet`) when the two differ.
  LoadParams placed_like(std::string_view gcode, const PrintConfig& cfg, bool quiet) const;
};

/// Presets by name from a vendor bundle (--printer-profile, --print-profile,
/// --material-profile, --profiles-dir), applied before any --load file, as PrusaSlicer does.
struct PresetOptions {
  std::string printer, print, material, dir = kDefaultProfilesDir;
  void add_to(CLI::App& cmd);
  /// Applies the named presets over `c` in PrusaSlicer's order (printer, print, filament);
  /// `keys` (if given) receives every key = value they set, for another slicer.
  Expected<void> apply(PrintConfig& c,
                       std::vector<std::pair<std::string, std::string>>* keys = nullptr) const;
};

/// The print profile a subcommand reads: --config FILE, then --set KEY=VALUE in order (any
/// PrusaSlicer key we read, and ours: the toolhead's keys, docs/toolhead.md).
struct ProfileOptions {
  PresetOptions presets;
  std::vector<std::string> config;  ///< profiles, each over the ones before it
  std::vector<std::string> sets;
  /// A subcommand's own options that are profile keys (--block-radius is
  /// heater_block_radius): key and the value given, applied before `sets`. A list, so the
  /// strings CLI11 writes into stay put.
  std::list<std::pair<std::string, std::string>> keyed;
  /// `what` names the subcommand's use of the profile in --config's help.
  void add_to(CLI::App& cmd, const std::string& what);
  /// Adds option `name` that sets profile key `key`.
  void add_keyed(CLI::App& cmd, const std::string& name, const std::string& key,
                 const std::string& help);
  /// The profile over `base`, with the overrides applied and validated; errors name the
  /// file or the key.
  Expected<PrintConfig> load(PrintConfig base = {}) const;
};

/// max_angle in (0, 90) degrees (NaN refused), or the error every subcommand gives.
Expected<void> check_max_angle(double max_angle_deg);

/// A section plane as --at gives it: "x=VALUE" or "y=VALUE" (mm). Errors: invalid_argument
/// naming --at.
struct SectionAt {
  char axis = 'y';
  double value = 0;
};
Expected<SectionAt> parse_section_at(const std::string& at);

/// One "KEY=VALUE" override; `known` is false for a key our settings do not have.
struct Setting {
  std::string key, value;
  bool known = true;
};
/// Applies "KEY=VALUE" to c; the error names the key ("--set: …" for a malformed pair). An
/// unknown key is an error unless `unknown_ok` (then it comes back with known = false, for
/// another slicer to take).
Expected<Setting> apply_setting(PrintConfig& c, const std::string& kv, bool unknown_ok = false);

/// The analysis stage's options (--max-angle, --tau, ...), added to a subcommand.
void add_analysis_options(CLI::App& cmd, AnalysisParams& p);

/// Refuses to write any output over an input or over another output (the same file by any
/// name: a link, "./x", an absolute path). Empty names are ignored. The error names both.
/// The file `-o OUTPUT` names for `model`: a folder (an existing one, or a path ending in '/')
/// gets "[input_filename_base].gcode" in it, and PrusaSlicer's output-name macros are
/// expanded ([input_filename_base], [input_filename], any profile key: [layer_height]).
/// Error: "-o OUTPUT: problem" (an unknown variable, for example).
Expected<std::string> output_path(const std::string& output, const std::string& model,
                                  const PrintConfig& cfg);

Expected<void> check_outputs(const std::vector<std::string>& inputs,
                             const std::vector<std::string>& outputs);

/// Flushes stdout; false (after printing "error: stdout: REASON") when what was printed did
/// not all arrive (`> /dev/full`, a closed pipe).
bool flush_stdout();

/// Prints "error: MESSAGE" on stderr; returns the exit code for the status.
int report_error(const Error& e);
/// Prints "warning: FILE: MESSAGE" for each loader warning (unless quiet).
void report_warnings(const std::string& file, const LoadedMesh& m, bool quiet);
/// A Context that stops on Ctrl-C and draws a progress line on stderr when it is a terminal and not
/// quiet.
Context make_context(bool quiet);
/// Clears the progress line, if one was drawn.
void finish_progress();

/// The printer a G-code file was sliced for, from its own settings block (PrusaSlicer's, and
/// so our engine route's): its bed centre is where the part was placed. Defaults when it has
/// none or the block does not read (a notice says why, unless quiet).
PrintConfig file_config(const std::string& file, std::string_view gcode, bool quiet);

/// The GLIBC_TUNABLES build/nonplanar set for this process (apps/launcher), out of the
/// environment the slicers it runs inherit: glibc has read it already.
void forget_launcher_tunables();

}  // namespace nonplanar::cli
