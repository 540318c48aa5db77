// The whole non-planar pipeline of DESIGN.md §2 as one call: analysis → fit → layers →
// normalisation → planar slicing → toolpaths → mapping back → safety check.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "nonplanar/check.hpp"
#include "nonplanar/deform.hpp"
#include "nonplanar/engine.hpp"
#include "nonplanar/gcode.hpp"
#include "nonplanar/layers.hpp"
#include "nonplanar/program.hpp"

namespace nonplanar {

/// One line the pipeline has for the user, about one patch or the whole part.
struct Notice {
  enum class Kind {
    setting,        ///< a setting was adapted to the printer (make_job)
    patch_planar,   ///< the patch prints planar, and why
    none_needed,    ///< no surface needs curved layers: the part slices planar
    none_fit,       ///< no patch could get a stack (a shell may still print it)
    shell,          ///< a shell was printed
    shell_refused,  ///< a shell was tried and refused, and why
    summary,        ///< the last word: how many curved patches printed curved, when not all
  };
  Kind kind = Kind::setting;
  int patch = -1;            ///< the patch it is about (-1: the part, or several patches)
  std::string text;          ///< the line as printed, e.g. "patch 3 printed planar: ..."
  bool names_a_fix = false;  ///< it names a setting and a value that would print it curved
};

/// How close to a limit the safety gate lets a printed path come (DESIGN.md §3): what the
/// file's rounding to µm may add, and no more.
struct GateParams {
  /// A layer may be this much thinner than h_min or thicker than h_max, mm.
  double thickness_slack = 1e-3;
  /// An extrusion may be this much steeper than max_angle, degrees.
  double angle_slack_deg = 0.5;
  /// The slope is judged over segments at least this long in XY, mm (a shorter one's slope is
  /// the rounding of its ends).
  double slope_run = 0.05;
  /// The most moves near curved layers the gate holds in memory for its passes over them
  /// (26 MB); past that each pass reads the program's text again.
  std::size_t held_moves = 250000;
};

struct SliceJob {
  AnalysisParams analysis;
  FitParams fit;
  LayerParams layers;           ///< layer heights and printer limits; set from print by make_job
  MapBackParams map_back;       ///< mapping paths and another engine's G-code back; by make_job
  CheckParams check;            ///< the safety gate's limits and head; set by make_job
  GateParams gate;              ///< how near those limits the gate lets a path come
  std::vector<Notice> notices;  ///< what make_job adapted (passed on to the result)
  PrintConfig print;
  bool planar_only = false;
  /// A part with no curved stack may print as a shell over a planar core.
  bool shells = true;
  /// Only a shell one slicer run can print with its core (prepare_part): one shell, and only
  /// where the part stands nowhere above its top.
  bool one_run_shells = false;
  /// Another slicer instead of the built-in engine: it slices the normalised mesh with the
  /// user's profile and its G-code is mapped back (map_foreign_gcode). Layer heights and
  /// the bed come from `print`, which must agree with that profile.
  EngineParams engine;
  /// More lines for the G-code's header, after the pipeline's own (the CLI names the model).
  std::vector<std::string> header;
  /// A plate of several objects (object_outlines of the mesh given to slice_model): the
  /// built-in engine prints each layer object by object, labelled with print.gcode's
  /// objects. Empty: one object.
  std::vector<ObjectOutline> objects;
  /// Keep SliceResult::layers' paths once the program is written from them. false: each
  /// layer keeps its z and height, and its paths go before the safety gate's collision
  /// search, for a caller that needs only the G-code (the CLI: on the bunny that phase's peak
  /// fell from 177 to about 100 MB).
  bool keep_paths = true;
};

/// A job whose layer and check settings agree with the print configuration: heights, the
/// toolhead, and a slope limit no steeper than the nozzle's cone (max_angle is lowered to
/// nozzle_cone_angle when the cone is flatter, with a notice).
SliceJob make_job(const PrintConfig& print, double max_angle_deg = 30.0);

struct SliceResult {
  std::vector<LayerToolpaths> layers;
  LayerPlan plan;
  std::vector<Notice> notices;      ///< fallbacks, planar because ..., shells; in order
  std::vector<std::string> header;  ///< for the G-code's header comment
  double thickness_min = 0, thickness_max = 0, steepest_deg = 0;
  std::size_t collisions = 0;
  bool nonplanar = false;
  int shell_layers = 0;    ///< curved layers of a shell over a planar core (0: none)
  int curved_patches = 0;  ///< patches whose surface needs curved layers (0 with planar_only)
  int printed_curved = 0;  ///< of those, the ones printed curved (as stacks or in the shell)
  PrintStats stats;        ///< time and filament of `gcode` (with_print_stats)
  /// `gcode` carries them already: the gate measured them beside its collision search.
  bool stats_in_gcode = false;
  /// The layers hold their z and height only: their paths went once `gcode` was written from
  /// them (SliceJob::keep_paths false).
  bool paths_released = false;
  /// The whole program, as the safety gate checked it: the built-in writer's, or an external
  /// engine's (its start and end G-code and settings kept) mapped back. Write it with
  /// write_gcode_text.
  std::string gcode;
};

/// Runs the pipeline on a mesh already placed on the bed. A violation of the printer limits
/// in the final paths is an internal_error naming where (no G-code should be written then).
Expected<SliceResult> slice_model(const TriangleMesh& mesh, const SliceJob& job,
                                  const Context& ctx);

}  // namespace nonplanar
