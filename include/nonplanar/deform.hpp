// Stage deform ("plane normalisation", DESIGN.md §2 step 5): map the mesh so the curved
// layers become planar, (x, y, z) ↦ (x, y, ζ(T(x, y, z))), subdividing where the map bends.
#pragma once

#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "nonplanar/context.hpp"
#include "nonplanar/layers.hpp"
#include "nonplanar/program.hpp"
#include "nonplanar/toolpaths.hpp"

namespace nonplanar {

struct NormalizeParams {
  /// Max distance between the mapped mesh and the exact map, mm: the map moves points in z only,
  /// so an edge's midpoint off by dz lies dz·|n_z| from its faces' planes (n their unit normals
  /// as mapped), and a steep wall's section moves by no more than that over its sine.
  double tolerance = 0.01;
  int max_rounds = 12;  ///< edge-splitting rounds at most
  /// Refused (unsupported) when a round leaves more faces than this; 0: no limit.
  std::size_t max_faces = 0;
  /// Faces whose XY box misses [care_min, care_max] are mapped at their corners only, never
  /// split (what is sliced of them there is not used: a shell's region lies inside), mm.
  Vec2 care_min = Vec2::Constant(-1e300), care_max = Vec2::Constant(1e300);
};

/// What a shell's map may take: at most max(500 000, 4 × the part's) faces. A shell over
/// Benchy's 16 curved patches split its 225 154 faces into 5.2 million (11.7 s, 600 MB) when
/// every long edge in a curved region was split and the error was measured in z; now 870 784
/// (the CurviSlicer car's nine make 74 102 of 13 934, the bunny's back 88 010 of 1872).
NormalizeParams shell_normalize_params(const TriangleMesh& mesh);

struct NormalizedMesh {
  TriangleMesh mesh;
  std::size_t edges_split = 0;
  int rounds = 0;
};

struct MapBackParams {
  double tolerance = 0.01;  ///< max distance of a straight segment from its curved layer, mm
  /// The plan's h_min (mm; 0: none): where a layer comes within 2·tolerance of it, its chords
  /// keep within half the margin (0.0005 mm at least), so consecutive layers' extrusions cross
  /// no closer than h_min less the gate's slack.
  double min_layer_height = 0;
  /// Curved segments whose layer is within 0.05 mm of min_layer_height are probed this far
  /// apart (mm; 0: the midpoint only), so a dip of the faceted top off a segment's middle
  /// still splits it (the gate measures what is left).
  double probe_spacing = 0.25;
  // Travels over curved layers (travel_height, toolhead.hpp); mm.
  double tip_radius = 0.4;   ///< the nozzle tip's flat (Toolhead::tip_radius)
  double travel_lift = 0.3;  ///< over the layer's highest point: travel_lift(retract_lift)
  /// Another slicer's G-code: where a layer under a shell is cut, when the passes retract.
  LayerPassParams passes;
  /// The points a mapped file may have (a count): past it the file is refused as broken.
  std::size_t most_points = 50'000'000;
};

/// Maps toolpaths sliced from the normalised mesh back onto the curved layers:
/// (x, y, ζ) ↦ (x, y, z(x, y, t(ζ))), splitting segments until each stays within the
/// tolerance of its layer; each point's height becomes the local layer thickness there, so
/// extrusion follows it. Top skins on a slope are reordered to print from low to high.
Expected<std::vector<LayerToolpaths>> map_toolpaths_back(const std::vector<LayerToolpaths>& planar,
                                                         const LayerField& field,
                                                         const MapBackParams& params,
                                                         const Context& ctx);

/// Another slicer's G-code of the normalised mesh, mapped back, and its extrusions (as paths
/// with heights, for the same safety check as the built-in engine's).
struct ForeignGcode {
  /// The mapped program in its three blocks: the start (up to the print's first
  /// ;LAYER_CHANGE), the print (its layers, written from steps), the end (the end G-code, the
  /// E reset before it included). Two runs join by their blocks (the shell route).
  std::string start, print, end;
  std::vector<LayerToolpaths> layers;  ///< one per ;LAYER_CHANGE of the print, in print order
  /// Per layer of `layers`: 1 where ForeignMapOptions::before_layer gave it (empty: none).
  std::vector<char> inserted;
  /// The whole program: start, print and end as one text.
  std::string text() const { return start + print + end; }
  /// The same after `head`, taking the blocks' text (no copy of the print kept).
  std::string take_text(std::string_view head = {});
  bool relative_e_at_print = false, relative_e_at_end = false;
  double e_at_print = 0;     ///< the file's E when the print starts (absolute E), mm
  std::string fan_at_print;  ///< the start G-code's last M106/M107 line (empty: none)
  Vec3 end_at{0, 0, 0};      ///< the nozzle when the print ends, mapped, mm
  /// Filament the print's own retractions leave pulled back when it ends (its start G-code's
  /// state not counted), mm.
  double retracted = 0;
};

/// A planar file's layers cut back to part of the plane: the shell's core (layers/shell_plan.hpp)
/// when another slicer prints it.
class LayerClip {
 public:
  enum class Cover { all, none, some };
  virtual ~LayerClip() = default;
  /// For the planar layer whose top is z (mm): keep all of it, none, or where margin >= 0.
  virtual Cover cover(double z) const = 0;
  /// Continuous in x, y; >= 0 where the layer with top z is kept (mm).
  virtual double margin(double x, double y, double z) const = 0;
  /// At least |∇margin(·, ·, z)| anywhere in the box [lo, hi] (mm per mm); infinity (the
  /// default) when not known, and every move is then looked at step by step.
  virtual double slope_bound(const Vec2& lo, const Vec2& hi, double z) const {
    (void)lo, (void)hi, (void)z;
    return std::numeric_limits<double>::infinity();
  }
};

struct ForeignMapOptions {
  /// Extrusions kept only where it says (the rest become travels; a layer with none kept is
  /// left out but for its M-codes). Null: keep everything.
  const LayerClip* clip = nullptr;
  /// Where the nozzle really is when the print starts (mapped, mm), when another program ran
  /// before this one's print: moves are written from there, not from where its start G-code
  /// left it.
  std::optional<Vec3> start;
  /// Filament already pulled back when the print starts (mm): given back with the first
  /// retraction move or before the first extrusion.
  double start_retracted = 0;
  /// Moves left where the file has them, by 0-based line of the file (1: keep): another
  /// object on the plate than the one the field was planned for. Travels to them are still
  /// lifted over curved layers. Empty: every move is mapped.
  std::vector<char> planar_lines;
  /// The file is read this many layers at a time (GcodePieceReader), their moves mapped side
  /// by side (one by one, clipped), then written: only those layers' lines, moves and paths are
  /// held (the bunny through PrusaSlicer: 64 layers held up to 131 000 moves, 16 MB; 32 took
  /// its peak from 160-170 MB to 152-162 MB, map back 0.86-1.0 s either way).
  std::size_t layers_at_once = 32;
  /// Paths printed between the file's layers, where they lie (mapped; each point's height the
  /// thickness under it): a shell's pieces where the part stands above its top
  /// (shell_pieces_with_engine, engine/shell_engine.hpp). Called before each layer of the print
  /// with the file's ;Z: of it, and after the last with +inf, with where the nozzle is; returns
  /// what to print there, in order, each piece a layer of the gate's (empty: nothing). They are
  /// written as the built-in writer writes paths: a travel lifted over what is printed, retracted
  /// by the file's first retraction on the way (its length owed to the file's next E after the
  /// last, so its own retractions balance as written); the nozzle then waits lifted over them until
  /// the file's next move in X or Y, which travels lifted. Null: nothing.
  std::function<std::vector<LayerToolpaths>(double z, const Vec3& at)> before_layer;
  /// Filament per mm of an inserted path of width w, height h (mm): filament_per_mm
  /// (gcode.hpp) with the print's settings. Needed with before_layer.
  std::function<double(double w, double h)> filament_per_mm;
  /// The travels to inserted paths, mm/s (their speeds are the paths' own).
  double inserted_travel_speed = 150;
};

/// Maps a planar G-code file (PrusaSlicer's or OrcaSlicer's, or ours) sliced from the
/// normalised mesh back onto the curved layers. Start and end G-code (before the first
/// ;LAYER_CHANGE; from the ;TYPE:Custom after the last extrusion type) pass untouched, as do
/// M-codes, tool changes, G4, G10/G11, G92 and the comments. Inside the print every G0/G1 is
/// mapped: extrusions resampled and their E scaled by each piece's 3D length and layer
/// thickness (as the built-in engine's paths), wipes laid on the layer, retractions kept,
/// travels over curved layers lifted above them; ;Z: and ;HEIGHT: are recomputed (the
/// layer's highest point and mean thickness); absolute or relative E as the file says.
/// Errors (parse_error, naming the line): an arc, an unknown command or word inside the
/// print, a move before the first layer, a file without ;LAYER_CHANGE. The file is read and
/// mapped a piece at a time, so of two faults the earlier in the file is the one named (an
/// arc past the layer where the mapped points pass most_points is not).
Expected<ForeignGcode> map_foreign_gcode(std::string_view text, const LayerField& field,
                                         const MapBackParams& params, const Context& ctx,
                                         const ForeignMapOptions& options = {});
/// The same, consuming the text: the memory of what has been read goes back to the system as
/// the map goes, and the text is gone when it returns (an engine's file, read once).
Expected<ForeignGcode> map_foreign_gcode_consuming(std::string&& text, const LayerField& field,
                                                   const MapBackParams& params, const Context& ctx,
                                                   const ForeignMapOptions& options = {});

/// Splits every edge whose mapped midpoint is farther than the tolerance from the mapped
/// chord (conforming: both faces of an edge split it), then maps every vertex. A closed,
/// consistently oriented input stays so. Errors: invalid_argument, cancelled.
Expected<NormalizedMesh> normalize_mesh(const TriangleMesh& mesh, const LayerField& field,
                                        const NormalizeParams& params, const Context& ctx);

}  // namespace nonplanar
