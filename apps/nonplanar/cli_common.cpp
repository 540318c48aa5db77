#include "cli_common.hpp"

#include <malloc.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "core/atomic_file.hpp"
#include "core/sanitizers.hpp"
#include "engine/external_engine.hpp"
#include "nonplanar/macros.hpp"
#include "nonplanar/print_plan.hpp"
#include "nonplanar/unsupported_keys.hpp"

namespace nonplanar::cli {
namespace {
bool g_progress_drawn = false;
std::atomic<bool> g_interrupted{false};
std::atomic<bool> g_timed_out{false};
double g_max_time = 0, g_max_memory = 0;

constexpr unsigned kGraceSeconds = 10;  // after a stop request, before leaving regardless

// Leaving now: the temporary output goes; a running engine is killed instead, and its run
// (which returns at once) removes its folder and reports. Async-signal-safe calls only.
void leave_now(int code, const char* msg, std::size_t len) {
  if (kill_running_engine()) return;
  remove_pending_temporary_file();
  (void)!::write(STDERR_FILENO, msg, len);
  ::_exit(code);
}

// First Ctrl-C (or SIGTERM): ask the stages to stop; they return Status::cancelled and the
// atomic writer removes its temporary. Code that cannot be cancelled (lib3mf reading a
// file of nested components took 37 s) gets kGraceSeconds, then SIGALRM leaves anyway. A
// second Ctrl-C leaves at once.
extern "C" void on_interrupt(int) {
  if (g_interrupted.exchange(true)) {
    constexpr char msg[] = "\nerror: interrupted\n";
    return leave_now(kExitInterrupted, msg, sizeof msg - 1);
  }
  ::alarm(kGraceSeconds);
}

// SIGALRM: --max-time ran out (the same stop as Ctrl-C, reported as the limit), or the grace
// after a stop request did.
extern "C" void on_alarm(int) {
  if (g_interrupted.exchange(true)) {
    constexpr char limit[] = "\nerror: stopped by --max-time; the work could not be cancelled\n";
    constexpr char user[] = "\nerror: interrupted; the work could not be cancelled\n";
    if (g_timed_out) return leave_now(kExitBadInput, limit, sizeof limit - 1);
    return leave_now(kExitInterrupted, user, sizeof user - 1);
  }
  g_timed_out = true;
  ::alarm(kGraceSeconds);
}
}  // namespace

void install_interrupt_handler() {
  struct sigaction sa {};
  sa.sa_handler = on_interrupt;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  struct sigaction al {};
  al.sa_handler = on_alarm;
  sigemptyset(&al.sa_mask);
  sigaction(SIGALRM, &al, nullptr);
}

void add_limit_options(CLI::App& app, Limits& l) {
  app.add_option("--max-memory", l.max_memory_mb,
                 "Stop with exit 2 when the run needs more than this much memory (MB;\n"
                 "0: no limit). Address space, so allow room beyond the model's size")
      ->check(CLI::Range(0.0, 1e9));
  app.add_option("--max-time", l.max_time_s,
                 "Stop with exit 2 after this many seconds (0: no limit), as Ctrl-C stops")
      ->check(CLI::Range(0.0, 1e7));
}

namespace {
// glibc's allocator, tuned for a run that allocates and frees rasters and grids of a few MB
// over and over (a shell's planning makes a dozen per candidate): by default each of them is
// mapped afresh and every page of it faults in, 11 % of the airfoil's samples in the kernel.
// Blocks up to 4 MB now come from the heap, which keeps up to 16 MB free at its top and grows
// 16 MB at a time (address space: not under --max-memory, where it would eat the margin).
// Against glibc's defaults (farm-bench, with 2a5bf3b): airfoil 0.85 of its wall time, car 0.91,
// the bunny 0.97 with a lower peak (192 MB against 209); Benchy 1.10 (103 MB against 106).
// Keeping 512 MB and growing 64 MB was faster on Benchy (1.43 s against 1.59) but raised its
// peak to 136 MB, over PrusaSlicer's. MALLOC_*_ in the environment (glibc's own knobs) leave
// the defaults.
void tune_allocator(bool memory_limited) {
#if defined(__GLIBC__) && !defined(NONPLANAR_SHADOW_MEMORY)
  for (const char* knob : {"MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_", "MALLOC_TOP_PAD_"})
    if (std::getenv(knob)) return;
  mallopt(M_MMAP_THRESHOLD, 4 << 20);
  mallopt(M_TRIM_THRESHOLD, 16 << 20);
  if (!memory_limited) mallopt(M_TOP_PAD, 16 << 20);
#else
  (void)memory_limited;
#endif
}

}  // namespace

void forget_launcher_tunables() {
  if (!std::getenv("NONPLANAR_SET_TUNABLES")) return;
  ::unsetenv("GLIBC_TUNABLES");
  ::unsetenv("NONPLANAR_SET_TUNABLES");
}

bool install_limits(const Limits& l) {
  tune_allocator(l.max_memory_mb > 0);
  g_max_memory = l.max_memory_mb, g_max_time = l.max_time_s;
  if (l.max_memory_mb > 0) {
#if defined(NONPLANAR_SHADOW_MEMORY)
    std::fprintf(stderr, "warning: --max-memory is not enforced in a sanitizer build\n");
#else
    const auto bytes = static_cast<rlim_t>(l.max_memory_mb * 1048576.0);
    const struct rlimit r { bytes, bytes };
    if (::setrlimit(RLIMIT_AS, &r) != 0) {
      std::fprintf(stderr, "error: --max-memory: %s\n", std::strerror(errno));
      return false;
    }
#endif
  }
  if (l.max_time_s > 0) {  // on_alarm is installed with the interrupt handler
    struct itimerval t {};
    t.it_value.tv_sec = static_cast<time_t>(l.max_time_s);
    t.it_value.tv_usec = static_cast<suseconds_t>((l.max_time_s - std::floor(l.max_time_s)) * 1e6);
    setitimer(ITIMER_REAL, &t, nullptr);
  }
  return true;
}

int report_out_of_memory() {
  remove_pending_temporary_file();  // the writer may have been what ran out
  if (g_max_memory > 0) {
    std::fprintf(stderr, "error: the run needs more than --max-memory %g MB; nothing was written\n",
                 g_max_memory);
    return kExitBadInput;
  }
  std::fprintf(stderr, "error: out of memory\n");
  return kExitFailure;
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

LoadParams MeshOptions::placed_like(std::string_view gcode, const PrintConfig& cfg,
                                    bool quiet_here) const {
  LoadParams lp = load;
  lp.bed_center = cfg.bed_center();
  if (const auto centre = post_processed_centre(gcode)) {
    if (!quiet_here && (*centre - lp.bed_center).norm() > 1e-3)
      std::fprintf(stderr, "the mesh centred at %.3f, %.3f mm, where the file's header puts it\n",
                   centre->x(), centre->y());
    lp.bed_center = *centre;
  }
  return lp;
}

void PresetOptions::add_to(CLI::App& cmd) {
  cmd.add_option("--printer-profile", printer,
                 "A printer preset by name from a vendor bundle (e.g. \"Original Prusa i3 MK3S &\n"
                 "MK3S+\"), its inherits chain resolved");
  cmd.add_option("--print-profile", print, "A print preset by name (e.g. \"0.20mm QUALITY @MK3\")");
  cmd.add_option("--material-profile", material,
                 "A filament preset by name (e.g. \"Prusament PLA\")");
  cmd.add_option("--profiles-dir", dir,
                 "Vendor bundles to find presets in: a folder of .ini or one .ini")
      ->capture_default_str();
}

Expected<void> PresetOptions::apply(PrintConfig& c,
                                    std::vector<std::pair<std::string, std::string>>* keys) const {
  for (const auto& [type, name] :
       {std::pair{"printer", &printer}, {"print", &print}, {"filament", &material}}) {
    if (name->empty()) continue;
    auto found = find_preset(dir, type, *name);
    if (!found) return found.error();
    for (const auto& [k, v] : *found) {
      auto r = set_config_value(c, k, v);
      if (!r)
        return Error{r.error().status,
                     std::string(type) + " preset '" + *name + "': " + r.error().message};
      if (keys) keys->emplace_back(k, v);
    }
  }
  return {};
}

void ProfileOptions::add_to(CLI::App& cmd, const std::string& what) {
  presets.add_to(cmd);
  cmd.add_option("--load,--config", config,
                 "Profile: PrusaSlicer .ini or OrcaSlicer/flat .json (" + what +
                     "); repeat it for a printer, a print and a filament file, each over the "
                     "ones before");
  cmd.add_option("--set", sets,
                 "Any setting by its key, after the profile: --set KEY=VALUE (e.g.\n"
                 "nozzle_cone_angle=40, toolhead_shape=prusa-mk3s; docs/toolhead.md)");
}

Expected<Setting> apply_setting(PrintConfig& c, const std::string& kv, bool unknown_ok) {
  const auto eq = kv.find('=');
  if (eq == std::string::npos)
    return Error{Status::invalid_argument, "--set: expected KEY=VALUE, got '" + kv + "'"};
  Setting p{kv.substr(0, eq), kv.substr(eq + 1)};
  auto r = set_config_value(c, p.key, p.value);
  if (!r) return Error{Status::invalid_argument, "--" + r.error().message};
  p.known = *r;
  if (!p.known && !unknown_ok && !is_unsupported_key(p.key))
    return Error{Status::invalid_argument, "unknown setting '" + p.key + "'"};
  return p;
}

void ProfileOptions::add_keyed(CLI::App& cmd, const std::string& name, const std::string& key,
                               const std::string& help) {
  keyed.emplace_back(key, "");
  cmd.add_option(name, keyed.back().second, help);
}

Expected<PrintConfig> ProfileOptions::load(PrintConfig base) const {
  PrintConfig cfg = std::move(base);
  if (auto p = presets.apply(cfg); !p) return p.error();
  for (const std::string& file : config) {
    auto c = load_config(file, std::move(cfg));
    if (!c) return c.error();
    cfg = std::move(*c);
  }
  for (const auto& [key, value] : keyed)
    if (!value.empty())
      if (auto r = apply_setting(cfg, key + "=" + value); !r) return r.error();
  for (const std::string& kv : sets)
    if (auto r = apply_setting(cfg, kv); !r) return r.error();
  if (auto v = validate_config(cfg); !v) return v.error();
  return cfg;
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

Expected<void> check_max_angle(double max_angle_deg) {
  if (max_angle_deg > 0 && max_angle_deg < 90) return {};
  return Error{Status::invalid_argument, "max_angle: must be in (0, 90) degrees"};
}

Expected<SectionAt> parse_section_at(const std::string& at) {
  if (at.size() < 3 || (at[0] != 'x' && at[0] != 'y') || at[1] != '=')
    return Error{Status::invalid_argument, "--at: expected x=VALUE or y=VALUE"};
  SectionAt out;
  out.axis = at[0];
  try {
    std::size_t used = 0;
    out.value = std::stod(at.substr(2), &used);
    if (used != at.size() - 2 || !std::isfinite(out.value)) throw std::invalid_argument(at);
  } catch (...) {
    return Error{Status::invalid_argument, "--at: '" + at.substr(2) + "' is not a number"};
  }
  return out;
}

namespace {
// The same file: the same inode where both exist, else the same path once resolved.
bool same_file(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) return fs::equivalent(a, b, ec) && !ec;
  const fs::path ca = fs::weakly_canonical(a, ec);
  if (ec) return false;
  const fs::path cb = fs::weakly_canonical(b, ec);
  return !ec && ca == cb;
}
}  // namespace

Expected<std::string> output_path(const std::string& output, const std::string& model,
                                  const PrintConfig& cfg) {
  namespace fs = std::filesystem;
  std::string out = output;
  std::error_code ec;
  if (!out.empty() && (out.back() == '/' || fs::is_directory(out, ec)))
    out = (fs::path(out) / "[input_filename_base].gcode").string();
  if (out.find_first_of("[{") == std::string::npos) return out;
  MacroVariables vars = profile_variables(cfg);
  const fs::path in(model);
  vars.set("input_filename_base", MacroValue::text(in.stem().string()));
  vars.set("input_filename", MacroValue::text(in.filename().string()));
  auto e = expand_macros(out, vars, "output name");
  if (!e) return Error{Status::invalid_argument, "-o " + output + ": " + e.error().message};
  if (e->empty() || e->back() == '/')
    return Error{Status::invalid_argument, "-o " + output + ": names no file"};
  return *e;
}

Expected<void> check_outputs(const std::vector<std::string>& inputs,
                             const std::vector<std::string>& outputs) {
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    if (outputs[i].empty()) continue;
    for (const std::string& in : inputs)
      if (!in.empty() && same_file(in, outputs[i]))
        return Error{Status::invalid_argument,
                     outputs[i] + ": is the input " + in + "; it would be overwritten"};
    for (std::size_t j = 0; j < i; ++j)
      if (!outputs[j].empty() && same_file(outputs[j], outputs[i]))
        return Error{Status::invalid_argument,
                     outputs[i] + ": is also " + outputs[j] + "; two outputs cannot share a file"};
  }
  return {};
}

bool flush_stdout() {
  errno = 0;
  if (std::fflush(stdout) == 0 && !std::ferror(stdout)) return true;
  std::fprintf(stderr, "error: stdout: %s\n", errno ? std::strerror(errno) : "write failed");
  return false;
}

int report_error(const Error& e) {
  if (e.status == Status::cancelled && g_timed_out) {
    std::fprintf(stderr, "error: stopped after --max-time %g s; nothing was written\n", g_max_time);
    return kExitBadInput;
  }
  if (e.status == Status::cancelled) {
    std::fprintf(stderr, "error: interrupted; nothing was written\n");
    return kExitInterrupted;
  }
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
  ctx.cancel_flag = &g_interrupted;
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

PrintConfig file_config(const std::string& file, std::string_view gcode, bool quiet) {
  const std::string block = gcode_config_block(gcode);
  if (block.empty()) return {};
  auto c = parse_ini_config(block);
  if (c) return std::move(*c);
  if (!quiet)
    std::fprintf(stderr, "notice: %s: its settings block is not used: %s\n", file.c_str(),
                 c.error().message.c_str());
  return {};
}

}  // namespace nonplanar::cli
