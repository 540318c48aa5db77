// Another slicer as the planar engine (issue: libslic3r engine): PrusaSlicer's or OrcaSlicer's
// command line slices the normalised mesh with the user's own profile; the caller maps the
// G-code back (deform/map_foreign_gcode.cpp).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "nonplanar/config.hpp"
#include "nonplanar/context.hpp"
#include "nonplanar/engine.hpp"
#include "nonplanar/mesh.hpp"

namespace nonplanar {

/// The settings forced on the engine's run, as "key = value" lines for the output's header.
std::vector<std::string> engine_forced_settings(const EngineParams& e, const PrintConfig& c);

/// What one run asks of the engine beyond the profile (PrusaSlicer only: OrcaSlicer's command
/// line cannot say it).
struct EngineRun {
  /// The layers' tops z_1 < z_2 < … (mm, the mesh's own z; its lowest point is z_0), given as a 3MF
  /// layer-height profile; past the last, layers of layer_height up to the mesh's top. Empty:
  /// first_layer_height, then layer_height.
  std::vector<double> layer_tops;
  /// > 0: the height of the layers past the last of layer_tops (mm; a shell's slab's). 0: the
  /// print's layer_height.
  double layer_height = 0;
  /// Volumes of the mesh's object under which the engine generates no supports (PrusaSlicer's
  /// SupportBlocker), in the mesh's coordinates; given with layer_tops only (an AMF or 3MF).
  std::vector<TriangleMesh> support_blockers;
  /// Called on the caller's thread when the engine has its input (the pipes written and their
  /// text freed, or the files written and the engine started), before its run is waited for
  /// (again if a run started early is made again from files): work beside the run starts there, not
  /// beside the input's text (Benchy's AMF and its shell's curved layers at once peaked at 155 MB,
  /// PrusaSlicer's 118).
  std::function<void()> handed_over;
};

/// PrusaSlicer's layer-height profile (Metadata/Slic3r_PE_layer_heights_profile.txt) of the
/// 3MF's first object: layers ending at `tops` (mm over the object's lowest point, rising),
/// then `h` thick up to `top`. Each layer's height is exact (two equal points a layer).
std::string layer_height_profile(const std::vector<double>& tops, double h, double top);

/// What the shell route asks of its run (header lines); first_layer: the core's first layer
/// height, mm; pieces: the shells' pieces go between the core's layers
/// (shell_pieces_with_engine), not in the same run.
std::vector<std::string> engine_shell_settings(double first_layer, bool pieces = false);

/// A PrusaSlicer run started before its mesh exists: it loads its libraries and the profile
/// (0.13 s of its 0.38 s on the sine roof) while the pipeline plans the layers, then reads the
/// run's layer heights (an ini) and the mesh (AMF text, with a layer-height profile when the
/// run has one) from two pipes (it reads an STL or a 3MF with a seek), and writes what it
/// writes of the STL or 3MF. Owned by the caller; stopped (SIGKILL: it waits for its input)
/// and its folder removed when dropped unused.
struct EarlyEngine;
struct EarlyEngineDeleter {
  void operator()(EarlyEngine* p) const;
};
using EarlyEnginePtr = std::unique_ptr<EarlyEngine, EarlyEngineDeleter>;

/// Starts PrusaSlicer for a run of `mesh` or of a mesh made from it by moving its vertices in
/// z only (the normalised one, or the part itself as a shell's core: its XY box centred where
/// this one's is), with e and c as run_engine will be given them. Null for OrcaSlicer, for a
/// mesh PrusaSlicer would repair (open, non-manifold or inconsistently wound edges: it repairs
/// an STL and not an AMF) unless `layer_tops` (then one that reads the 3MF a run with layer
/// tops is given, and takes only such a run: for a run known to come, as a shell's core), or
/// when it cannot start (run_engine then starts its own and reports what goes wrong).
EarlyEnginePtr start_engine_early(const EngineParams& e, const PrintConfig& c,
                                  const TriangleMesh& mesh, bool layer_tops = false);

/// Inputs: the engine, the mesh to slice (lowest point on the bed; its XY box centre stays
/// where it is), the print settings it must agree with (layer heights), what this run asks.
/// Output: the G-code text the engine wrote. Runs the engine in a temporary folder (removed
/// afterwards) in a process group of its own, and stops the group on cancellation (SIGTERM,
/// SIGKILL after 3 s). Errors: io_error (engine missing, failed: its last output line; a
/// file without the statistics or config block a slicer writes after the last layer, i.e.
/// truncated), cancelled. `early`: an engine start_engine_early started with the same e and c;
/// a run of a mesh centred where it expects takes it (once), else it is left alone; when it fails,
/// the run starts its own from files, as without it.
Expected<std::string> run_engine(const EngineParams& e, const TriangleMesh& mesh,
                                 const PrintConfig& c, const Context& ctx,
                                 const EngineRun& run = {}, EarlyEngine* early = nullptr);

/// Hands the engine started early `run` of `mesh` now, before the caller knows it needs it (a
/// shell core's boundaries, foreseen while the shells are planned): the run goes on beside the
/// caller, and the run_engine call given `early` with the same mesh (object) and run (layer tops
/// and height, no blockers) takes its G-code (its handed_over called at once). Any other call
/// given `early` stops it first and starts its own engine. The mesh, e and c must outlive
/// `early`. Nothing is done when `early` was taken or expects a mesh centred elsewhere.
void run_engine_ahead(EarlyEngine& early, const EngineParams& e, const TriangleMesh& mesh,
                      const PrintConfig& c, EngineRun run, const Context& ctx);

/// Whether `early` (null: no) has a run handed over ahead, neither taken nor stopped yet.
bool engine_ahead(const EarlyEngine* early);

/// For a signal handler (async-signal-safe): SIGKILL the running engines' process groups (an
/// early one may wait); each run_engine() then returns and
/// removes its folder. True if one ran.
bool kill_running_engine();

}  // namespace nonplanar
