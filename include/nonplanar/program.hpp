// The print program in the middle (issue: one print program for both engines). Read: G-code
// as lines and moves, by the one tolerant reader (`check`, the gate, and the mapping of another
// slicer's G-code read so). Written: a start block, then layers of steps (ProgramLayer:
// extrusions, travels, retractions, lines kept as written), then an end block, through the one
// writer; the built-in engine and the mapping of another slicer's file both build their layers
// as steps. Units: mm, mm of filament for E, mm/min for feed rates (as written).
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "nonplanar/mesh.hpp"
#include "nonplanar/polygon.hpp"
#include "nonplanar/status.hpp"
#include "nonplanar/toolhead.hpp"
#include "nonplanar/toolpaths.hpp"

namespace nonplanar {

/// "No value given": a feed rate or an E the line did not have.
inline constexpr double kNoValue = std::numeric_limits<double>::quiet_NaN();

/// One G0/G1 line as read (or made): where it went and what it pushed. Its members are ordered
/// widest first: a file's moves are held whole (656 000 of them for the bunny through
/// PrusaSlicer), at 120 bytes each rather than 136.
struct GcodeMove {
  Vec3 from{0, 0, 0}, to{0, 0, 0};
  double de = 0;           ///< filament pushed (negative: retraction), mm
  double f = kNoValue;     ///< the line's own F word (kNoValue: none)
  double feed = kNoValue;  ///< the feed rate in force for it (its own or the last one given)
  double width = 0.45;     ///< the ;WIDTH: in force, mm
  /// The planar thickness under it: the latest ;HEIGHT: in force (PrusaSlicer gives a layer
  /// that follows a support-only layer its distance from that, and the part's beads in it
  /// their own); a bridge's or overhang's ;HEIGHT: is not taken (it is the round bead's, the
  /// nozzle's diameter), mm.
  double height = 0.2;
  std::string_view type;  ///< the ;TYPE: in force ("" before any); views the text read
  int line = 0;           ///< 1-based line of the file (0: made in memory)
  int layer = -1;         ///< ;LAYER_CHANGE count − 1
  bool has_xy = false, has_z = false, has_e = false;  ///< the words the line had
  bool wipe = false;                                  ///< between ;WIPE_START and ;WIPE_END
  /// Pushes filament while moving in XY.
  bool extruding() const { return de > 0 && has_xy && (to - from).head<2>().norm() > 1e-9; }
};

/// One line of the program, classified. `raw` is the line as written (no line end). Widest
/// members first, as GcodeMove's: 40 bytes a line.
struct GcodeLine {
  enum class Kind : std::uint8_t {
    text,            ///< passes as written: comments, M-codes, T, macros, G4, G28, ...
    move,            ///< G0/G1: moves[move]
    z_comment,       ///< the layer's ;Z: (inside the print)
    height_comment,  ///< the layer's ;HEIGHT: (inside the print, the first after its change)
    e_reset,         ///< G92 with E: value is the new E
    e_mode,          ///< M82 / M83: value 1 for relative
    xyz_relative,    ///< G91 (which makes E relative too)
  };
  std::string_view raw;
  double value = 0;
  int move = -1;
  int layer = -1;  ///< ;LAYER_CHANGE count − 1 at this line
  Kind kind = Kind::text;
};

/// A line the reader could not take: what the caller refuses depends on where it is.
struct GcodeProblem {
  int line = 0;  ///< 1-based
  std::string why;
  /// G28 / G29 (home, probe) move the head by themselves: fine before or after the print,
  /// not inside it (nothing can map them). Other problems make the file unreadable.
  bool moves_head = false;
};

/// The reader's state at one point of the file.
struct GcodeState {
  double e = 0;  ///< absolute E, mm
  bool relative_e = false, relative_xyz = false;
  double feed = kNoValue;  ///< the feed rate in force
};

/// The file's first retraction inside the print (length 0: none).
struct GcodeRetraction {
  double length = 0;         ///< mm of filament
  double f = kNoValue;       ///< its feed rate
  double back_f = kNoValue;  ///< the feed rate that gives it back
};

/// A whole G-code file as the one reader sees it. The views point into the text read, which
/// must outlive the program.
struct GcodeProgram {
  std::vector<GcodeLine> lines;  ///< one per line of the file
  std::vector<GcodeMove> moves;  ///< every G0/G1, in order
  std::vector<GcodeProblem> problems;
  /// The print: from its first ;LAYER_CHANGE line (lines.size() when there is none) up to
  /// the ;TYPE:Custom after the last other ;TYPE: (PrusaSlicer's and OrcaSlicer's end G-code
  /// follow one), else the end of the file. Line indices, 0-based.
  std::size_t print_begin = 0, print_end = 0;
  GcodeState at_print, at_end;    ///< when the print starts; when it ends
  std::string_view fan_at_print;  ///< the start G-code's last M106/M107 line ("" when none)
  /// Per layer of the print: its ;HEIGHT: (the planar thickness) and ;Z: (its top), mm.
  std::vector<double> layer_height, layer_z;
  GcodeRetraction retraction;
  bool in_print(std::size_t line_index) const {
    return line_index >= print_begin && line_index < print_end;
  }
};

/// The one G-code reader, tolerant as a slicer's viewer is: PrusaSlicer's, OrcaSlicer's,
/// Klipper's and our own files. Comments ;TYPE:, ;WIDTH:, ;HEIGHT:, ;Z:, ;LAYER_CHANGE,
/// ;WIPE_START/END set what the moves carry; G90/G91, G92, M82/M83 are tracked (G91 makes E
/// relative too, as Klipper, RepRapFirmware and PrusaSlicer's viewer read it). M-codes
/// (dotted ones too: M862.3), T, Klipper macros (SET_PRINT_STATS_INFO, EXCLUDE_OBJECT_START:
/// upper-case names, or lower-case ones with an underscore) and motionless G-codes pass as
/// text. Never fails: what it cannot take (arcs, inches, unknown G-codes, junk, a bad number
/// or unknown word in a move) is listed in `problems`, each with its line; home and probe
/// (G28, G29) too, marked moves_head.
GcodeProgram read_gcode_program(std::string_view text);

/// One G1 line of a program being written: where it goes and the words it writes.
struct ProgramMove {
  Vec3 to{0, 0, 0};
  double de = kNoValue;  ///< filament pushed, mm (kNoValue: no E word)
  double f = kNoValue;   ///< feed rate, mm/min (kNoValue: no F word)
  /// An extrusion's layer thickness at `to` (the built-in engine's paths, mapped pieces), mm;
  /// 0 where not known.
  double height = 0;
  bool xy = false, z = false;     ///< write X Y; write Z
  const char* comment = nullptr;  ///< written after " ; " (a string literal)
};

/// One step of a layer: what one or more G-code lines do.
struct ProgramStep {
  enum class Kind : std::uint8_t {
    raw,             ///< text kept as written, its lines ended: comments, M-codes, blocks
    z_comment,       ///< ";Z:<value>": the layer's top, %.3f
    height_comment,  ///< ";HEIGHT:<value>": its thickness, %.3f
    e_reset,         ///< raw text that sets the E counter to `value` (G92 E)
    e_mode,          ///< raw text that makes E relative (`value` 1) or absolute (0)
    travel,          ///< moves that push nothing (a lifted travel: up, across, down); the
                     ///< last may give back a retraction
    extrusion,       ///< moves pushing filament along one path of `role`, `width`
    retract,         ///< one move, E only: pulls filament back (de < 0) or gives it back
  };
  Kind kind = Kind::raw;
  /// raw, e_reset, e_mode: bytes [begin, end) of the layer's text; travel, extrusion,
  /// retract: its moves [begin, end).
  std::uint32_t begin = 0, end = 0;
  double value = 0;                               ///< z_comment, height_comment, e_reset, e_mode
  ExtrusionRole role = ExtrusionRole::perimeter;  ///< extrusion
  double width = 0;                               ///< extrusion, mm
  bool moves() const { return kind >= Kind::travel; }
};

/// One layer of a program as steps, built by an engine (or by mapping another slicer's layer)
/// and written by write_program_layer (program/gcode_text.hpp). The writer keeps E (absolute
/// or relative) across layers, so a layer's steps carry E as pushed, never as a counter.
class ProgramLayer {
 public:
  std::vector<ProgramStep> steps;
  std::vector<ProgramMove> moves;  ///< the move steps' moves, in order
  std::string text;                ///< the text steps' bytes
  /// A line longer than 255 characters was given: the program must be refused.
  bool too_long = false;

  void clear();
  /// One line (its end added) / lines already ended (a custom G-code block), as written.
  void raw(std::string_view line);
  void block(std::string_view lines);
  /// printf into one line (at most 255 characters, else too_long).
  void line(const char* fmt, ...) __attribute__((format(printf, 2, 3)));
  /// ;Z: and ;HEIGHT: lines; the value can be set later (steps[index].value).
  std::size_t z_comment(double z);
  std::size_t height_comment(double h);
  /// A line that sets E (G92 E…), or its mode (M82 / M83): kept as written, and followed.
  void e_reset(std::string_view line, double e);
  void e_mode(std::string_view line, bool relative);
  /// Starts a step of moves; move() and move_from() add to it.
  void start(ProgramStep::Kind kind, ExtrusionRole role = ExtrusionRole::perimeter,
             double width = 0);
  void move(const ProgramMove& m);
  /// A move from `from` to p that writes only the axes that change by more than 0.5 µm (what
  /// %.3f can show), E and F where given; nothing when no word is left.
  void move_from(const Vec3& from, const Vec3& p, double de, double f, double height = 0);
  /// A travel that clears a curved layer: up to `lift` where the nozzle is (at), across at
  /// that height, down to `to` (pushing `de` there, if given: a retraction given back).
  /// `f_first` on the first line, `f_rest` on the others (kNoValue: none). Its own step.
  /// travel_height (toolhead.hpp) says how high.
  void lifted_travel(const Vec3& at, const Vec3& to, double lift, double f_first, double f_rest,
                     double de = kNoValue);

 private:
  void text_step(ProgramStep::Kind kind, std::string_view bytes, double value);
};

/// The first thing inside the print (p.in_print) that cannot be mapped onto curved layers, as
/// a parse_error naming its line: a problem the reader listed (an arc, home or probe, junk, a
/// bad word), or a coordinate beyond 10 m (no printer is that large, and mapping its moves in
/// 1 mm pieces would not fit in memory; a move's start counts too, as the start G-code may
/// have left the nozzle there). Nothing when all of it can.
std::optional<Error> first_unmappable(const GcodeProgram& p);

/// The same reading, streamed line by line for a caller that needs every line but not all of
/// them at once (the statistics of a large file): f gets each line in order, with its move
/// when it is one (else null); the views point into `text`. Returns the program without its
/// lines and moves (print_begin, print_end, problems and the per-file figures).
GcodeProgram for_each_gcode_line(std::string_view text,
                                 const std::function<void(const GcodeLine&, const GcodeMove*)>& f);

/// The one reader, a piece of a file at a time, for a caller that goes through a large file in
/// order and needs every line, but not all of them at once (the mapping of another slicer's
/// file: the bunny's 967 000 lines and 656 000 moves through PrusaSlicer, held whole, were
/// 118 MB of the engine route's peak). The pieces, in order: the start (the lines before the
/// print), the print a few layers at a time, the end (from print_end). After each, program()
/// holds only the piece's lines, moves and problems (lines[k] is the file's line
/// first_line() + k; a line's `move` indexes the piece's moves) and the figures read so far:
/// print_begin and print_end from the first, at_print once the start is read, the layers'
/// layer_z and layer_height and the retraction so far, at_end with the end. The reading is
/// read_gcode_program's, line for line. The text must outlive the reader and the program.
class GcodePieceReader {
 public:
  enum class Piece { start, layers, end };
  explicit GcodePieceReader(std::string_view text);
  ~GcodePieceReader();
  GcodePieceReader(const GcodePieceReader&) = delete;
  GcodePieceReader& operator=(const GcodePieceReader&) = delete;
  /// Reads the next piece (the start and the end may be empty); in the print, at most `layers`
  /// layers (at least one). False when the whole file has been read.
  bool next(std::size_t layers);
  Piece piece() const;
  /// The file's line (0-based) that the piece's first line is.
  std::size_t first_line() const;
  /// The first byte of the text that the reader still views (the piece's first line, or the
  /// ;TYPE: in force, which its moves and the next pieces' view, if earlier): what lies before
  /// it is never read again, and its memory may go (map_foreign_gcode's consuming form).
  std::size_t held_from() const;
  /// The print's layers (its ;LAYER_CHANGE lines), known from the start.
  std::size_t layer_count() const;
  GcodeProgram& program();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// How many lines a text has, and how many of them start with a G (an upper bound of the
/// moves any reading of it finds): room to reserve before reading it, once.
struct GcodeLineCount {
  std::size_t lines = 0, g_lines = 0;
};
GcodeLineCount count_gcode_lines(std::string_view text);

/// The thresholds of the passes that rewrite a layer being mapped onto curved layers
/// (layer_passes.hpp: clip_layer, order_top_skins). mm unless named otherwise.
struct LayerPassParams {
  /// Where a layer under a shell is cut: the margin is looked at every clip_step along a move,
  /// then each change of side is bisected.
  double clip_step = 0.05;
  /// A stretch cut away that is longer than this is travelled retracted, as PrusaSlicer's
  /// retract_before_travel (2 mm) would have it.
  double clip_retract_over = 2.0;
  /// The margins a whole file may look up (a count, not mm): past it the file is refused as
  /// broken, not a print (a print needs a few million).
  std::size_t most_clip_samples = 50'000'000;
  /// A travel between two reordered top-skin strokes longer than this is retracted around.
  double skin_retract_over = 1.0;
  /// The head, whose reach says which strokes of a top skin are ordered (low_to_high).
  Toolhead head;
};

/// One G0/G1 move with what it deposited (check's input).
struct PrintMove {
  Vec3 from{0, 0, 0}, to{0, 0, 0};
  double filament = 0;     ///< mm of filament pushed (negative: retraction)
  bool extruding = false;  ///< filament > 0 and the nozzle moved in XY
  bool wipe = false;       ///< between ;WIPE_START and ;WIPE_END
  std::string_view type;   ///< the ;TYPE: in force ("" before any); views the text read
  int layer = -1;          ///< ;LAYER_CHANGE count − 1
  double width = 0.45;     ///< ;WIDTH: in force
  int line = 0;            ///< 1-based line in the file (0 for moves made in memory)
};

/// The same reading, streamed: f gets every G0/G1 in order and nothing else is kept, for a
/// caller that wants only some moves of a large file. Returns the problems.
std::vector<GcodeProblem> for_each_gcode_move(std::string_view text,
                                              const std::function<void(const GcodeMove&)>& f);

/// A move as check reads it: the GcodeMove's ends, filament, type (viewing the same text),
/// layer, width and line.
PrintMove print_move(const GcodeMove& g);

/// The moves of a file as check reads them, one at a time to f, among those `keep` accepts
/// (null: all). Problems are not looked at (for a file this program wrote or mapped itself).
void for_each_print_move(std::string_view text, const std::function<bool(const GcodeMove&)>& keep,
                         const std::function<void(const PrintMove&)>& f);

/// The moves of a G-code file, through read_gcode_program (their types view `text`, which
/// must outlive them). Refused (parse_error naming the
/// line): any problem but home and probe (arcs, inches, unknown G-codes, junk).
Expected<std::vector<PrintMove>> read_gcode_moves(std::string_view text);

// A plate of several objects (a 3MF's build items): whose each path is, and each layer printed
// object by object, as PrusaSlicer prints a plate, so each can be labelled and cancelled.

/// An object seen from above: its box, and where another object's box overlaps it, its
/// shadow on a raster over the box (a cell is set where some face's XY shadow, grown by half a
/// cell's diagonal, touches it). mm.
struct ObjectOutline {
  BoundingBox box;
  Vec2 origin{0, 0};  ///< the raster's corner (cell (0, 0) spans origin … origin + cell)
  double cell = 0;
  int nx = 0, ny = 0;
  std::vector<char> shadow;  ///< nx·ny cells, (i, j) at i·ny + j; empty: no raster
  /// Whether (x, y) is in the shadow (with no raster: in the box).
  bool covers(const Vec2& p) const;
};

/// The most objects a plate prints apart: each path looks at every object's box.
inline constexpr std::size_t kMostPlateObjects = 256;

/// One outline per object of `objects` (objects.face: an index per face of `mesh`); none when
/// the plate holds one object, or more than kMostPlateObjects (it then prints as one object).
/// Rasters of 0.2 mm cells (coarser past 4 million a raster).
std::vector<ObjectOutline> object_outlines(const TriangleMesh& mesh, const PlateObjects& objects);

/// The object a point prints: the one whose footprint holds it in XY, among those whose box
/// it is in (or nearest to, for a point between footprints); 0 with one outline or none.
int object_at(const std::vector<ObjectOutline>& outlines, const Vec3& p);

/// Sets each path's `object` (by the point halfway along it; the skirt's stay 0) and orders
/// each layer's paths by object, stably and with the skirt first: a layer prints one object
/// after another, each in its own order. Nothing changes with fewer than two outlines.
void group_by_object(std::vector<LayerToolpaths>& layers,
                     const std::vector<ObjectOutline>& outlines);

}  // namespace nonplanar
