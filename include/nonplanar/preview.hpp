// Stage preview: a G-code file as a person wants to see it, in one self-contained HTML page
// (WebGL, no network at view time). The page counts the file's own layers (its ;LAYER_CHANGE
// order), not its Z values, so a curved print of 47 layers has a slider of 47 steps.
//
// Notation: a segment is one G0/G1 move that moved in XY or Z; its slope is
// atan(|Δz| / |Δxy|); its thickness is the bead height h whose rounded-rectangle section
// (w − h)·h + π·h²/4 holds the filament it pushed (Slic3r's flow model, width w = ;WIDTH:).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "nonplanar/mesh.hpp"
#include "nonplanar/program.hpp"

namespace nonplanar {

/// How the buffers are made.
struct PreviewParams {
  double filament_diameter = 1.75;  ///< mm, to turn E into a bead's section
  /// A layer whose extrusions span more than this in z is curved (planar layers print at
  /// one z; the file's z has 3 decimals), mm.
  double curved_span = 0.005;
  bool travels = true;  ///< keep travel moves (the page hides them until asked)
};

/// Per segment of the file, in file order, ready for the GPU. Positions are quantised to 16
/// bits over `box` (4.6 µm over 300 mm): p = box.min + q / 65535 · box.size().
struct PreviewBuffers {
  BoundingBox box;                      ///< of every kept segment's end points, mm
  std::vector<std::uint16_t> ends;      ///< 6 per segment: from xyz, to xyz (quantised)
  std::vector<std::uint16_t> layer;     ///< our layer index, 0-based (moves before the first
                                        ///< ;LAYER_CHANGE count as layer 0)
  std::vector<std::uint8_t> role;       ///< index into role_names
  std::vector<std::uint8_t> flags;      ///< kTravel | kCurvedLayer
  std::vector<std::uint8_t> thickness;  ///< bead height, 5 µm units (0: travel), ≤ 1.275 mm
  std::vector<std::uint8_t> width;      ///< bead width (;WIDTH:), 10 µm units, ≤ 2.55 mm
  std::vector<std::uint8_t> slope;      ///< degrees, 0–90
  std::vector<float> time;              ///< s from the start when the segment ends
  std::vector<std::string> role_names;  ///< the ;TYPE: names in order of first use ("Custom"
                                        ///< for moves before any ;TYPE:)
  int layers = 0;                       ///< ;LAYER_CHANGE count (at least 1 when any move)
  int curved_layers = 0;                ///< layers whose extrusions in the print (not the
                                        ///< start or end G-code) span > curved_span in z
  std::vector<float> layer_z;           ///< per layer: lowest such extrusion z (a layer
                                        ///< without one: its ;Z:), mm
  double filament_mm = 0;               ///< net E over the file
  double seconds = 0;                   ///< the estimate's total (0 when not given)
  std::size_t segments() const { return layer.size(); }

  static constexpr std::uint8_t kTravel = 1, kCurvedLayer = 2;
};

/// The segments of `program` (read by read_gcode_program). `line_time` is
/// PrintTime::line_start of the same program (empty: no times). Moves that only retract or
/// only change the feed rate are left out. Errors: none; a file with no move gives no
/// segment and layers = 0.
PreviewBuffers preview_buffers(const GcodeProgram& program, const std::vector<double>& line_time,
                               const PreviewParams& params);

/// What check found, to be marked where it is.
struct PreviewMarks {
  std::vector<Vec3> collisions;  ///< mm, placed like the G-code
  std::vector<Vec3> breaches;    ///< limit breaches (thickness, slope), mm
};

/// The numbers the page's panel shows beside its own counts.
struct PreviewSummary {
  std::string title;          ///< the G-code's file name
  double p95 = -1;            ///< top-surface deviation p95, mm (< 0: not measured)
  long long collisions = -1;  ///< as counted by check or the slicer's gate (< 0: not
                              ///< measured; marks hold at most 4096 of them)
  double filament_g = 0;      ///< 0: unknown density
  double max_angle_deg = 30;  ///< the slope colour scale's top
  /// The bed, drawn as a grid at z = 0: x0, y0, x1, y1 in mm (all 0: not drawn).
  std::array<double, 4> bed{0, 0, 0, 0};
};

/// The self-contained page: the viewer (viewer.html, built in), the buffers base64-encoded,
/// `mesh` shown translucent when not null (placed like the G-code), the marks and the
/// summary. Size: about 30 bytes per segment and 10 per mesh triangle.
std::string preview_html(const PreviewBuffers& buffers, const TriangleMesh* mesh,
                         const PreviewMarks& marks, const PreviewSummary& summary);

/// A vertical cross-section of the printed beads, as SVG: every extrusion segment of `b` that
/// crosses the plane (axis 'x' or 'y' = value, mm) drawn as its bead's section there (its
/// width in the plane × its thickness, the top at the segment's z), curved layers orange and
/// planar ones blue, alternate layers lighter; with `mesh` (placed like the G-code), its
/// outline in the plane. Errors: invalid_argument for another axis or a plane no extrusion
/// crosses.
Expected<std::string> bead_section_svg(const PreviewBuffers& b, const TriangleMesh* mesh, char axis,
                                       double value);

}  // namespace nonplanar
