#include "engine/external_engine.hpp"

#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <thread>

#include "core/ahead_run.hpp"
#include "core/mesh_topology.hpp"
#include "nonplanar/io.hpp"

extern char** environ;

namespace nonplanar {
namespace {

namespace fs = std::filesystem;

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// A temporary folder, removed with everything in it when this goes out of scope.
struct TempDir {
  fs::path path;
  TempDir() {
    std::string t = (fs::temp_directory_path() / "nonplanar-engine-XXXXXX").string();
    if (mkdtemp(t.data())) path = t;
  }
  ~TempDir() {
    std::error_code ec;
    if (!path.empty()) fs::remove_all(path, ec);
  }
};

// The engines' process groups while they run (each its own group, so that a terminal's Ctrl-C
// reaches us, not them, and we stop each with everything it started), for
// kill_running_engine(): a slot each (an early one may wait beside a run started late).
constexpr int kEngineSlots = 4;
std::atomic<pid_t> g_engine_group[kEngineSlots]{};

// Stops the engine's whole group: SIGTERM, and SIGKILL if it has not gone within 3 s (an
// engine that ignored SIGTERM once kept running, and kept its folder, after Ctrl-C).
void stop_engine(pid_t pid, int* status) {
  ::kill(-pid, SIGTERM);
  for (int i = 0; i < 150; ++i) {
    if (waitpid(pid, status, WNOHANG) == pid) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ::kill(-pid, SIGKILL);
  waitpid(pid, status, 0);
  // What the engine started is not our child: it dies on its own time, which on a loaded
  // machine outlasted our exit (a test found its sleep still running). Wait up to 1 s for the
  // group to go; a zombie that nobody reaps (a container without an init) is not waited for.
  for (int i = 0; i < 50 && ::kill(-pid, 0) == 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
}

// Did the engine write its file to the end? Every libslic3r slicer writes its statistics
// or config block after the last layer; a file without them stopped early (a crashed or
// killed engine, a full disk) and must not reach a printer with its heaters left on.
bool ends_complete(const std::string& text) {
  const auto last = text.rfind(";LAYER_CHANGE");
  if (last == std::string::npos) return false;
  for (const char* end : {"; filament used", "; prusaslicer_config = end", "; CONFIG_BLOCK_END",
                          "; EXECUTABLE_BLOCK_END"})
    if (text.find(end, last) != std::string::npos) return true;
  return false;
}

std::string last_line(const fs::path& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos &&
        line.find("[trace]") == std::string::npos)
      last = line;
  if (last.size() > 200) last = last.substr(0, 200) + "...";
  return last;
}

}  // namespace

std::vector<std::string> engine_forced_settings(const EngineParams& e, const PrintConfig& c) {
  if (e.engine == Engine::builtin) return {};
  // OrcaSlicer's command line cannot override them: they are what its profile must say.
  const std::string how = e.engine == Engine::orcaslicer ? "required of the profile, " : "";
  std::vector<std::string> s = {
      "layer_height = " + num(c.slice.layer_height) + " (the normalised layers)",
      "first_layer_height = " + num(c.slice.first_layer_height),
      "spiral_vase = 0",
      "retract_lift = 0 (travel lifts over curved layers are nonplanar's)",
      "arc_fitting = disabled",
      std::string("E distances: ") + (c.gcode.relative_e ? "relative" : "absolute") +
          " (as the profile says)"};
  for (std::string& v : s) v = how + v;
  return s;
}

std::vector<std::string> engine_shell_settings(double first_layer, bool pieces) {
  if (pieces)
    return {
        "core: one run of the part, its layer boundaries from a 3MF layer-height profile "
        "(where flat floors land), first_layer_height = " +
            num(first_layer),
        "shells: the built-in engine's curved layers, in pieces between the core's layers "
        "(where the part stands above them)"};
  return {
      "core and shell: one run, its layer boundaries from a 3MF layer-height profile (the "
      "core's, where flat floors land, then the shell's above them), first_layer_height = " +
      num(first_layer)};
}

namespace {

// The height of a run's layers past its layer tops (all of them, without tops).
double run_layer_height(const PrintConfig& c, const EngineRun& run) {
  return run.layer_height > 0 ? run.layer_height : c.slice.layer_height;
}

// Pairs (z, height) PrusaSlicer interpolates linearly, looked up a little above each layer's
// bottom; each layer gets two equal points (its bottom and middle), so its height is exact.
// "z;h;z;h;…", as a 3MF's profile holds them after its object and an AMF's metadata holds them.
std::string layer_height_pairs(const std::vector<double>& tops, double h, double top) {
  std::string s;
  char buf[64];
  double b = 0;
  auto layer = [&](double t) {
    std::snprintf(buf, sizeof buf, "%.6f;%.6f;%.6f;%.6f;", b, t, b + 0.5 * t, t);
    s += buf;
    b += t;
  };
  for (double z : tops)
    if (z > b + 1e-6) layer(z - b), b = z;
  while (b + h < top - 1e-6) layer(h);
  std::snprintf(buf, sizeof buf, "%.6f;%.6f", top, h);
  return s + buf;
}

}  // namespace

std::string layer_height_profile(const std::vector<double>& tops, double h, double top) {
  return "object_id=1|" + layer_height_pairs(tops, h, top) + "\n";
}

namespace {

// The flavour asked for is the flavour written: PrusaSlicer 2.5 reads gcode_flavor = klipper
// (2.6's) as its default, reprap, without a word, and the file would say so only in its
// last lines (#16).
std::optional<Error> flavor_kept(const PrintConfig& c, const std::string& gcode,
                                 const std::string& name) {
  const auto asked = c.profile.find("gcode_flavor");
  if (asked == c.profile.end()) return std::nullopt;
  const std::string block = gcode_config_block(gcode);
  const std::string key = "gcode_flavor = ";
  const auto at = block.find(key);
  if (at == std::string::npos || (at > 0 && block[at - 1] != '\n')) return std::nullopt;
  const std::string wrote = block.substr(at + key.size(), block.find('\n', at) - at - key.size());
  if (wrote == asked->second) return std::nullopt;
  return Error{Status::unsupported,
               "engine: " + name + " wrote gcode_flavor = " + wrote + ", not " + asked->second +
                   ": this " + name +
                   " cannot write that flavour (PrusaSlicer writes klipper "
                   "from 2.6 on); use --gcode-flavor marlin2 (Klipper reads it) or --engine "
                   "builtin"};
}

}  // namespace

namespace {

// One engine process: its folder (the input, its output and log), its process group's slot
// for kill_running_engine(); stopped, if still running, and its folder removed on destruction.
struct Launch {
  TempDir dir;
  fs::path input, out, log;
  fs::path settings;  ///< started early: the pipe it reads the run's layer heights from
  pid_t pid = 0;
  std::atomic<pid_t>* slot = nullptr;
  bool reaped = false;
  bool waiting = false;  ///< started early, never given its mesh: killed at once
  int status = 0;
  /// The folder made, the engine to read `input_name` in it.
  explicit Launch(const char* input_name)
      : input(dir.path / input_name), out(dir.path / "out.gcode"), log(dir.path / "engine.log") {}
  Launch(const Launch&) = delete;
  Launch& operator=(const Launch&) = delete;
  ~Launch() {
    if (pid > 0 && !reaped && waiting) {
      ::kill(-pid, SIGKILL);  // blocked opening its input: nothing of its own to save
      waitpid(pid, &status, 0);
    } else if (pid > 0 && !reaped) {
      stop_engine(pid, &status);
    }
    if (slot) slot->store(0);
  }
};

// The engine's command line for `run` of a mesh whose XY box is centred at `centre`, read
// from l.input (first_layer: the first layer's height, mm); PrusaSlicer's also writes
// forced.ini into the folder. With l.settings, PrusaSlicer reads the layer heights from that
// file after forced.ini (run_settings: a pipe written when the run is known) instead of the
// command line.
Expected<std::vector<std::string>> engine_args(const EngineParams& e, const PrintConfig& c,
                                               const EngineRun& run, const Launch& l,
                                               const Vec2& centre, double first_layer,
                                               const std::string& exe) {
  std::vector<std::string> args{exe};
  if (e.engine == Engine::orcaslicer) {
    // OrcaSlicer's documented command line (untested here: it is not packaged for Debian).
    args.insert(args.end(), {"--slice", "0", "--outputdir", l.dir.path.string()});
    if (!e.config.empty()) args.insert(args.end(), {"--load-settings", e.config});
    if (!e.filaments.empty()) args.insert(args.end(), {"--load-filaments", e.filaments});
    args.push_back(l.input.string());
    return args;
  }
  // The user's overrides and what we force go in a file loaded after the profile: there a
  // boolean reads "1" (on the command line it takes no value), and a key an older PrusaSlicer
  // does not know (arc_fitting, 2.6+) is ignored rather than fatal. What is on the command
  // line below overrides both.
  const fs::path forced = l.dir.path / "forced.ini";
  {
    std::ofstream ini(forced);
    // A key once, with its last value: presets by name and --set may both give it, and
    // PrusaSlicer refuses an ini with a duplicate key.
    std::map<std::string, std::size_t> last;
    for (std::size_t i = 0; i < e.overrides.size(); ++i) last[e.overrides[i].first] = i;
    for (std::size_t i = 0; i < e.overrides.size(); ++i) {
      const auto& [key, value] = e.overrides[i];
      if (last[key] == i && key != "retract_lift" && key != "spiral_vase" && key != "arc_fitting" &&
          key != "layer_height" && key != "first_layer_height")
        ini << key << " = " << value << "\n";
    }
    ini << "arc_fitting = disabled\n";
    if (!ini) return Error{Status::io_error, "engine: cannot write " + forced.string()};
  }
  args.push_back("--export-gcode");
  if (!e.config.empty()) args.insert(args.end(), {"--load", e.config});
  const double h = run_layer_height(c, run);
  args.insert(args.end(), {"--load", forced.string()});
  if (!l.settings.empty())
    args.insert(args.end(), {"--load", l.settings.string()});
  else
    args.insert(args.end(), {"--layer-height", num(h), "--first-layer-height", num(first_layer)});
  args.insert(args.end(), {"--retract-lift", "0", "--no-spiral-vase", "--center",
                           num(centre.x()) + "," + num(centre.y())});
  if (e.config.empty()) {
    char bed[160];
    std::snprintf(bed, sizeof bed, "%gx%g,%gx%g,%gx%g,%gx%g", c.bed_min.x(), c.bed_min.y(),
                  c.bed_max.x(), c.bed_min.y(), c.bed_max.x(), c.bed_max.y(), c.bed_min.x(),
                  c.bed_max.y());
    args.insert(args.end(), {"--bed-shape", bed, "--nozzle-diameter", num(c.paths.nozzle_diameter),
                             "--filament-diameter", num(c.gcode.filament_diameter)});
  }
  args.insert(args.end(), {"--output", l.out.string(), l.input.string()});
  return args;
}

// The engine's executable: --engine-path, else the one on PATH.
std::string engine_exe(const EngineParams& e) {
  return !e.path.empty() ? e.path : e.engine == Engine::orcaslicer ? "orca-slicer" : "prusa-slicer";
}

// Starts the engine (stdout and stderr to l.log) in a process group of its own.
Expected<void> spawn(Launch& l, std::vector<std::string> args, const std::string& name) {
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, l.log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
  posix_spawnattr_setpgroup(&attr, 0);  // a group of its own, led by the engine
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, argv[0], &fa, &attr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  posix_spawnattr_destroy(&attr);
  if (rc != 0)
    return Error{Status::io_error, "engine: cannot run '" + args[0] + "' (" + name +
                                       " not installed? --engine-path names it)"};
  l.pid = pid;
  for (int i = 0; i < kEngineSlots && !l.slot; ++i)
    if (pid_t none = 0; g_engine_group[i].compare_exchange_strong(none, pid))
      l.slot = &g_engine_group[i];
  return {};
}

// Has the engine exited (its status kept)?
bool exited(Launch& l) {
  if (!l.reaped && waitpid(l.pid, &l.status, WNOHANG) == l.pid) l.reaped = true;
  return l.reaped;
}

// The layer heights of a run whose engine reads them from l.settings (the --layer-height and
// --first-layer-height engine_args gives a run started late).
std::string run_settings(const PrintConfig& c, const EngineRun& run, double first_layer) {
  const double h = run_layer_height(c, run);
  return "layer_height = " + num(h) + "\nfirst_layer_height = " + num(first_layer) + "\n";
}

// Writes a pipe's text fully into it once opened (false: the engine stopped reading: it
// reports why).
Expected<bool> write_pipe(int fd, const std::string& text, const Context& ctx) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n =
        ::write(fd, text.data() + done, std::min<std::size_t>(text.size() - done, 1 << 16));
    if (n > 0) {
      done += static_cast<std::size_t>(n);
    } else if (n < 0 && errno == EAGAIN) {
      pollfd p{fd, POLLOUT, 0};
      ::poll(&p, 1, 20);
      if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
    } else if (!(n < 0 && errno == EINTR)) {
      return false;  // EPIPE: it stopped reading
    }
  }
  return true;
}

// Writes each (pipe, text) into its pipe as the engine opens it (after loading its libraries
// and profile: the time this saves), in whichever order it opens them. An engine that stopped
// before reading them all is left to finish() to report. A SIGPIPE the writes raise is dropped.
Expected<void> feed(Launch& l, std::vector<std::pair<fs::path, std::string>> pipes,
                    const Context& ctx) {
  sigset_t pipe_signal, old;
  sigemptyset(&pipe_signal);
  sigaddset(&pipe_signal, SIGPIPE);
  pthread_sigmask(SIG_BLOCK, &pipe_signal, &old);
  struct Restore {
    sigset_t &set, &old;
    ~Restore() {
      const timespec now{};
      while (sigtimedwait(&set, nullptr, &now) > 0) {
      }
      pthread_sigmask(SIG_SETMASK, &old, nullptr);
    }
  } restore{pipe_signal, old};
  while (!pipes.empty()) {
    // The first pipe the engine has opened for reading (open fails with ENXIO until then).
    std::size_t k = 0;
    int fd = -1;
    for (; k < pipes.size() && fd < 0; ++k) {
      fd = ::open(pipes[k].first.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC);
      if (fd < 0 && errno != ENXIO && errno != EINTR)
        return Error{Status::io_error, "engine: cannot write its input " + pipes[k].first.string()};
    }
    if (fd >= 0) {
      auto wrote = write_pipe(fd, pipes[k - 1].second, ctx);
      ::close(fd);
      if (!wrote) return wrote.error();
      if (!*wrote) return {};
      pipes.erase(pipes.begin() + static_cast<long>(k - 1));
      continue;
    }
    if (exited(l)) return {};
    if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return {};
}

// Waits for the engine (stopping it on cancellation) and reads its file.
Expected<std::string> finish(Launch& l, const EngineParams& e, const PrintConfig& c,
                             const Context& ctx) {
  const bool orca = e.engine == Engine::orcaslicer;
  const std::string name = orca ? "OrcaSlicer" : "PrusaSlicer";
  while (!exited(l)) {
    if (ctx.cancelled()) {
      stop_engine(l.pid, &l.status);
      l.reaped = true;
      return Error{Status::cancelled, "cancelled"};
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(orca ? 20 : 5));
  }
  fs::path result = l.out;
  if (orca) {  // it names its output itself (plate_1.gcode)
    result.clear();
    std::error_code ec;
    for (const auto& f : fs::directory_iterator(l.dir.path, ec))
      if (f.path().extension() == ".gcode") result = f.path();
  }
  if (!WIFEXITED(l.status) || WEXITSTATUS(l.status) != 0 || result.empty() || !fs::exists(result)) {
    const std::string why = last_line(l.log);
    return Error{Status::io_error, "engine: " + name + " failed" + (why.empty() ? "" : ": " + why)};
  }
  // Read into its own room (a string stream's buffer and its copy were 2.7 times the bunny's
  // 19 MB at once), with some over for the config block complete_config_block may add.
  std::string gcode;
  {
    std::ifstream in(result, std::ios::binary | std::ios::ate);
    const std::streamoff size = in ? static_cast<std::streamoff>(in.tellg()) : 0;
    gcode.reserve(static_cast<std::size_t>(std::max<std::streamoff>(size, 0)) + (64 << 10));
    gcode.resize(static_cast<std::size_t>(std::max<std::streamoff>(size, 0)));
    in.seekg(0);
    if (!in.read(gcode.data(), size))
      return Error{Status::io_error,
                   "engine: cannot read " + name + "'s G-code " + result.string()};
  }
  if (!ends_complete(gcode))
    return Error{Status::io_error,
                 "engine: " + name +
                     "'s G-code stops before its end (no statistics or config block after the "
                     "last layer): a truncated file is not printed"};
  if (auto f = flavor_kept(c, gcode, name)) return *f;
  complete_config_block(gcode, c);  // the file says what its time estimate assumed
  return gcode;
}

}  // namespace

struct EarlyEngine {
  explicit EarlyEngine(bool as_amf) : launch(as_amf ? "part.amf.xml" : "core.3mf"), amf(as_amf) {}
  Launch launch;
  /// Reads the mesh as AMF from a pipe; else from the 3MF a run with layer tops writes (a mesh
  /// PrusaSlicer would repair: it repairs what it reads from an STL and not from an AMF),
  /// written before the run's settings are: PrusaSlicer opens its input only once it has them.
  bool amf;
  Vec2 centre;
  std::atomic<bool> taken{false};
  /// Started beside a run handed over ahead, for the run that stops that one instead.
  EarlyEnginePtr spare;
  /// A run handed over ahead (run_engine_ahead): what it was given, and its G-code to come
  /// (none: the mesh could not go as AMF). Stopped before `launch` is.
  struct Ahead {
    const TriangleMesh* mesh = nullptr;
    EngineRun run;
    std::optional<core::AheadRun<std::optional<Expected<std::string>>>> gcode;
  };
  std::unique_ptr<Ahead> ahead;
};

void EarlyEngineDeleter::operator()(EarlyEngine* p) const {
  delete p;
}

EarlyEnginePtr start_engine_early(const EngineParams& e, const PrintConfig& c,
                                  const TriangleMesh& mesh, bool layer_tops) {
  if (e.engine != Engine::prusaslicer) return nullptr;
  // PrusaSlicer repairs an STL as it reads it (edges matched across small gaps, holes filled)
  // and an AMF not: the same G-code from both needs a mesh with nothing to repair (the
  // CurviSlicer car, open in places, came out 7 facets apart). Such a mesh goes as the 3MF a
  // run with layer tops started late reads, which PrusaSlicer opens after its settings pipe:
  // its start is hidden all the same, but it cannot take a run without layer tops (an STL),
  // so it is started only for a run known to come (on open meshes whose runs were STLs one
  // started unasked cost 29 % of the time).
  const MeshTopology t = build_topology(mesh);
  const bool repaired = t.open_edges || t.non_manifold_edges || t.inconsistent_edges;
  if (repaired && !layer_tops) return nullptr;
  const BoundingBox box = bounding_box(mesh);
  const Vec2 centre = 0.5 * (box.min + box.max).head<2>();
  EarlyEnginePtr early(new EarlyEngine(!repaired));
  Launch& l = early->launch;
  if (l.dir.path.empty()) return nullptr;
  l.settings = l.dir.path / "run.ini";
  if ((early->amf && ::mkfifo(l.input.c_str(), 0600) != 0) ||
      ::mkfifo(l.settings.c_str(), 0600) != 0)
    return nullptr;
  auto args = engine_args(e, c, EngineRun{}, l, centre, c.slice.first_layer_height, engine_exe(e));
  if (!args || !spawn(l, std::move(*args), "PrusaSlicer")) return nullptr;
  early->centre = centre;
  l.waiting = true;
  return early;
}

namespace {

// The tops of a run's layers over the lowest point of a mesh whose box is `box` (none: empty).
std::vector<double> run_tops(const BoundingBox& box, const EngineRun& run) {
  std::vector<double> tops;
  for (double z : run.layer_tops) tops.push_back(z - box.min.z());
  return tops;
}

// The 3MF of a run with layer tops: the mesh, its blockers, and the layer heights' profile.
Expected<void> write_run_file(const fs::path& to, const TriangleMesh& mesh, const BoundingBox& box,
                              const PrintConfig& c, const EngineRun& run) {
  const PackageFile f{"/Metadata/Slic3r_PE_layer_heights_profile.txt",
                      layer_height_profile(run_tops(box, run), run_layer_height(c, run),
                                           box.max.z() - box.min.z())};
  Object3mf object;
  object.support_blockers = run.support_blockers;
  return write_3mf(to, mesh, {f}, object);
}

// The run given to the engine started early: its layer heights, then the mesh as AMF (with
// the profile, if any), as the engine opens the two pipes; or, to one that reads a 3MF, that
// file and then its layer heights. Empty: it cannot take this run (faces that collapse in
// float: the STL of a run started late lets PrusaSlicer repair them; a run without layer tops
// for one that reads a 3MF: a run started late reads an STL).
std::optional<Expected<void>> hand_over(EarlyEngine& early, const TriangleMesh& mesh,
                                        const BoundingBox& box, const PrintConfig& c,
                                        const Context& ctx, const EngineRun& run,
                                        double first_layer) {
  if (!early.amf) {
    if (run.layer_tops.empty()) return std::nullopt;
    Launch& l = early.launch;
    if (auto w = write_run_file(l.input, mesh, box, c, run); !w) return Expected<void>(w.error());
    l.waiting = false;
    return feed(l, {{l.settings, run_settings(c, run, first_layer)}}, ctx);
  }
  std::size_t collapsed = 0;
  std::vector<std::pair<std::string, std::string>> metadata;
  if (!run.layer_tops.empty())
    metadata.emplace_back("slic3r.layer_height_profile",
                          layer_height_pairs(run_tops(box, run), run_layer_height(c, run),
                                             box.max.z() - box.min.z()));
  std::string amf = amf_text(mesh, &collapsed, metadata, run.support_blockers);
  if (collapsed != 0) return std::nullopt;
  Launch& l = early.launch;
  l.waiting = false;
  return feed(l, {{l.settings, run_settings(c, run, first_layer)}, {l.input, std::move(amf)}}, ctx);
}

// hand_over, then the engine's G-code.
std::optional<Expected<std::string>> run_early(EarlyEngine& early, const EngineParams& e,
                                               const TriangleMesh& mesh, const BoundingBox& box,
                                               const PrintConfig& c, const Context& ctx,
                                               const EngineRun& run, double first_layer) {
  auto fed = hand_over(early, mesh, box, c, ctx, run, first_layer);
  if (!fed) return std::nullopt;
  if (!*fed) return Expected<std::string>(fed->error());
  if (run.handed_over) run.handed_over();
  return finish(early.launch, e, c, ctx);
}

}  // namespace

void run_engine_ahead(EarlyEngine& early, const EngineParams& e, const TriangleMesh& mesh,
                      const PrintConfig& c, EngineRun run, const Context& ctx) {
  const BoundingBox box = bounding_box(mesh);
  if (e.engine != Engine::prusaslicer || 0.5 * (box.min + box.max).head<2>() != early.centre ||
      early.taken.exchange(true))
    return;
  const double h1 =
      run.layer_tops.empty() ? c.slice.first_layer_height : run.layer_tops.front() - box.min.z();
  // Another one waits for the run that is asked for if this one is not (its start is most of a
  // small part's run: the Voron cube's slice took 9 % longer without it).
  early.spare = start_engine_early(e, c, mesh);
  // A large mesh is handed over here, so that its AMF text is gone before the shells are
  // planned (beside them Benchy's 25 MB raised the peak from 114 to 154 MB); a small one beside
  // them, not waiting for the engine to be ready to read it (0.3 s on the bunny).
  constexpr std::size_t kLargeAmf = 8u << 20;  // bytes, at 72 a face (amf_text)
  using Fed = std::optional<Expected<void>>;
  std::optional<Fed> fed;
  if (72 * mesh.faces.size() > kLargeAmf) fed = hand_over(early, mesh, box, c, ctx, run, h1);
  early.ahead = std::make_unique<EarlyEngine::Ahead>();
  EarlyEngine::Ahead& a = *early.ahead;
  a.mesh = &mesh, a.run = std::move(run);
  a.gcode.emplace(ctx, [&early, &a, &e, &mesh, &c, box, h1,
                        fed = std::move(fed)](const Context& inner) mutable {
    using Result = std::optional<Expected<std::string>>;
    if (!fed) fed = hand_over(early, mesh, box, c, inner, a.run, h1);
    if (!*fed) return Result{};
    if (!**fed) return Result(Expected<std::string>((*fed)->error()));
    return Result(finish(early.launch, e, c, inner));
  });
}

bool engine_ahead(const EarlyEngine* early) {
  return early && early->ahead;
}

namespace {

// The G-code of the run handed over ahead, when this is that run (else that run is stopped,
// and `early` becomes the spare engine started beside it): none when it is not, or when it
// failed as run_early's runs may (run then as one started late).
std::optional<Expected<std::string>> take_ahead(EarlyEngine*& early, const TriangleMesh& mesh,
                                                const EngineRun& run) {
  if (!early || !early->ahead) return std::nullopt;
  const std::unique_ptr<EarlyEngine::Ahead> a = std::move(early->ahead);
  const bool same = a->mesh == &mesh && a->run.layer_tops == run.layer_tops &&
                    a->run.layer_height == run.layer_height && run.support_blockers.empty() &&
                    a->run.support_blockers.empty();
  if (!same) {  // (a's engine stopped as it goes)
    early = early->spare.get();
    return std::nullopt;
  }
  if (run.handed_over) run.handed_over();
  std::optional<Expected<std::string>> gcode = a->gcode->get();
  if (gcode && (*gcode || gcode->error().status != Status::io_error)) return gcode;
  early = early->spare.get();
  return std::nullopt;
}

}  // namespace

Expected<std::string> run_engine(const EngineParams& e, const TriangleMesh& mesh,
                                 const PrintConfig& c, const Context& ctx, const EngineRun& run,
                                 EarlyEngine* early) {
  if (auto gcode = take_ahead(early, mesh, run)) return std::move(*gcode);
  const bool orca = e.engine == Engine::orcaslicer;
  const BoundingBox box = bounding_box(mesh);
  // Where the part is: the engine centres its box there.
  const Vec2 centre = 0.5 * (box.min + box.max).head<2>();
  const bool profile = !orca && !run.layer_tops.empty();
  const double h1 = profile ? run.layer_tops.front() - box.min.z() : c.slice.first_layer_height;
  if (early && !orca && centre == early->centre && !early->taken.exchange(true))
    if (auto gcode = run_early(*early, e, mesh, box, c, ctx, run, h1))
      // A pipe that could not be written, or a PrusaSlicer that failed (one whose readers seek
      // in an ini or AMF too, or a bad profile): run again as before, from files; the user
      // gets its file, or what that run says.
      if (*gcode || gcode->error().status != Status::io_error) return std::move(*gcode);
  Launch l(profile ? "core.3mf" : "normalized.stl");
  if (l.dir.path.empty()) return Error{Status::io_error, "engine: cannot make a temporary folder"};
  if (profile) {
    if (auto w = write_run_file(l.input, mesh, box, c, run); !w) return w.error();
  } else if (auto w = write_stl(l.input, mesh); !w) {
    return w.error();
  }
  auto args = engine_args(e, c, run, l, centre, h1, engine_exe(e));
  if (!args) return args.error();
  if (auto s = spawn(l, std::move(*args), orca ? "OrcaSlicer" : "PrusaSlicer"); !s)
    return s.error();
  if (run.handed_over) run.handed_over();
  return finish(l, e, c, ctx);
}

bool kill_running_engine() {
  bool any = false;
  for (std::atomic<pid_t>& slot : g_engine_group)
    if (const pid_t g = slot.load(); g > 0) ::kill(-g, SIGKILL), any = true;
  return any;
}

}  // namespace nonplanar
