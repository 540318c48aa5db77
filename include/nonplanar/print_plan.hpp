// Curved tops from inside the user's own slicer (README, "Use it from PrusaSlicer /
// OrcaSlicer"): `prepare` plans the curved layers and writes the normalised part, which the
// slicer slices with the user's own profile; its post-processing script (`post-process`)
// maps the G-code back with the same plan. The plan travels in the 3MF
// (Metadata/nonplanar_plan.json, docs/plan-format.md). Units: mm, degrees.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "nonplanar/pipeline.hpp"

namespace nonplanar {

/// What post-process needs to know of the plan: the field, where the normalised part stood,
/// the layers it was planned for and the limits and head it was checked against.
struct PrintPlan {
  std::string object;  ///< the part's name in the 3MF (the model file's stem)
  std::string model;   ///< the model file prepare read (for messages)
  BoundingBox box;     ///< the normalised part on the bed, as prepare placed it
  double layer_height = 0.2, first_layer_height = 0.2;
  double min_layer_height = 0.1, max_layer_height = 0.3, max_angle_deg = 30;
  Toolhead toolhead;
  std::vector<std::string> header;  ///< what is curved, for the G-code's header
  std::string field;                ///< the layer field as text (field_io.hpp)
  /// A shell over a planar core instead of stacks (JSON text, docs/plan-format.md; empty:
  /// none). The slicer prints the core's layers on the shell plan's boundaries, one layer
  /// more (cut away: it only holds up the next) and the shell's layers as planes above them.
  std::string shell;
  /// Where the part stands, to find it again on the slicer's plate: the outline (the largest
  /// island's contour, counter-clockwise) of the part to slice, cut at the middle of its second
  /// layer, whose top is at anchor_z. Empty: none (the box alone places it).
  std::vector<Vec2> anchor;
  double anchor_z = 0;
};

/// The plan as JSON text (docs/plan-format.md).
std::string plan_json(const PrintPlan& plan);
/// Reads what plan_json wrote, every value checked. Errors: parse_error, unsupported (a
/// newer version).
Expected<PrintPlan> parse_plan_json(std::string_view text);

/// prepare's output: the normalised part to slice, and its plan.
struct PreparedPart {
  /// The part to slice: for stacks, normalised; for a shell, the part itself with the
  /// shell's normalised slab above it (from the top of the core's layers up).
  TriangleMesh normalized;
  PrintPlan plan;
  /// The plan's stacks' field (plan.field as read back); null for a shell (plan.shell).
  std::shared_ptr<const LayerField> field;
  std::vector<Notice> notices;  ///< as slice_model's (patches printed planar and why)
  std::size_t stacks = 0;       ///< curved stacks in the plan
  int shell_layers = 0;         ///< a shell's curved layers (0: no shell)
  /// PrusaSlicer's layer-height profile for the part (Slic3r_PE_layer_heights_profile.txt;
  /// empty: none, the layers are the plan's layer_height).
  std::string layer_heights_profile;
  /// A shell's support blocker: a box over the part from just above the core's last boundary
  /// up, where the slicer would otherwise support the slab's underside (it stands above the
  /// part in the 3MF) and the columns under it. Empty without a shell.
  TriangleMesh support_blocker;
};

/// Inputs: the part placed on the bed, the job (its engine slices the plan to check it,
/// retries and all, as `slice` does: the built-in one, or PrusaSlicer with the user's profile,
/// whose paths are the ones post-process will map). Output: the part to slice and the plan of
/// the stacks that passed, or of one shell over a planar core where `slice` would print one
/// and one slicer run can (nothing of the part stands above the shell's top: the slicer
/// prints the core's layers, then the shell's). Errors: unsupported when nothing prints curved
/// (the message says why), those of slice_model, cancelled.
Expected<PreparedPart> prepare_part(const TriangleMesh& placed, SliceJob job, const Context& ctx);

/// What post_process_gcode did.
struct PostProcessed {
  std::string gcode;       ///< the whole file, mapped back
  Vec2 moved{0, 0};        ///< where the slicer put the part relative to the plan, mm
  std::size_t layers = 0;  ///< layers of the print
  double thickness_min = 0, thickness_max = 0, steepest_deg = 0;
  PrintStats stats;
  /// What it changed beyond the mapping, one line each (supports it left out).
  std::vector<std::string> notices;
};

/// Maps a slicer's G-code of the prepared part back onto the curved layers (the same passes
/// as `slice --engine`: map_foreign_gcode, the safety gate, the time and filament). The
/// printer and its limits come from the file's own settings block; the layers, limits and
/// head from the plan. Refused (invalid_argument, naming the setting or what to change): a
/// file already post-processed, no settings block, another layer height or first layer
/// height, arc fitting, spiral vase, variable layer height, a part scaled or rotated (its
/// extrusions' box against the plan's), other objects without labels to tell them apart; a
/// violation of the limits (internal_error names where).
Expected<PostProcessed> post_process_gcode(std::string_view gcode, const PrintPlan& plan,
                                           const Context& ctx);

/// The objects a G-code file's labels name (PrusaSlicer's comments, M486, Klipper's
/// EXCLUDE_OBJECT_*), without the slicer's id, copy and file extension ("dome id:0 copy 0" is
/// "dome"), in order of first appearance; empty without labels. Bambu Lab's labels ("; start
/// printing object, unique label id: N", OrcaSlicer's and Bambu Studio's) name none: post-process
/// takes the one object of the plan's size as the part.
std::vector<std::string> gcode_object_names(std::string_view gcode);

/// The first line post_process_gcode writes (how a file already post-processed is known).
inline constexpr std::string_view kPostProcessedMark = "; post-processed by nonplanar";

/// Where the planned part's box is centred on the plate (mm, XY) in a file post_process_gcode
/// or `nonplanar slice` wrote (by either engine), as its header says (kPartCentredAt); none
/// for another file. `check` and `preview` place the mesh there, whatever printer profile the
/// file was sliced for.
std::optional<Vec2> post_processed_centre(std::string_view gcode);
inline constexpr std::string_view kPartCentredAt = "; the part's box centred at ";
/// The first line `nonplanar slice` writes (the built-in engine's; an engine's goes on).
inline constexpr std::string_view kGeneratedMark = "; generated by nonplanar";

}  // namespace nonplanar
