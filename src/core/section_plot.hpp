// A vertical section of a part as an SVG picture: the frame (axes in mm) and the mesh's
// outline in the plane, shared by the pictures that draw layers in it (the plan's boundaries,
// layers/section_svg.cpp; the printed beads, preview/bead_section.cpp).
//
// Notation: the plane is x = value or y = value; s is the other horizontal coordinate, the
// picture's horizontal axis; z is up.
#pragma once

#include <array>
#include <ostream>
#include <string>
#include <vector>

#include "nonplanar/mesh.hpp"

namespace nonplanar::core {

/// (s, z) in mm to SVG pixels: s0 … s1 across `width_px`, z from 0 to z1, 70 px of margin on
/// the left and 50 on top.
struct SectionFrame {
  double s0 = 0, s1 = 1, z1 = 1;
  double scale = 1;  ///< px per mm
  double left = 70, top = 50;
  SectionFrame(double s_lo, double s_hi, double z_top, double width_px);
  double X(double s) const { return left + (s - s0) * scale; }
  double Y(double z) const { return top + (z1 - z) * scale; }
  double width() const { return (s1 - s0) * scale + 110; }  ///< the picture's, px
  double height() const { return z1 * scale + 110; }        ///< the picture's, px
};

/// The plane's cut through every triangle of `mesh` it crosses: segments (s_a, z_a, s_b, z_b),
/// mm. axis 'x' or 'y'.
std::vector<std::array<double, 4>> section_outline(const TriangleMesh& mesh, char axis,
                                                   double value);

/// The SVG's opening (white background) and `title` over the frame; then axes with ticks in mm
/// and their names. Close with svg_end.
void svg_begin(std::ostream& svg, const SectionFrame& f, const std::string& title, char s_name);
/// The outline segments in black, and the closing tag.
void svg_end(std::ostream& svg, const SectionFrame& f,
             const std::vector<std::array<double, 4>>& outline);

}  // namespace nonplanar::core
