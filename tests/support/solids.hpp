// Analytic test solids built in memory: height-field blocks, boxes, spheres. Every solid is
// closed and outward-oriented, so tests know its exact top surface and volume.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

#include "nonplanar/config.hpp"
#include "nonplanar/mesh.hpp"

namespace nonplanar::test {

/// Closed block over [x0,x1]×[y0,y1]: top z = f(x, y) on an nx × ny grid of quads, flat
/// bottom at z = base, vertical walls. Requires f > base.
TriangleMesh height_field_solid(const std::function<double(double, double)>& f, double x0,
                                double x1, double y0, double y1, int nx, int ny, double base = 0.0);

/// m moved as the CLI places a part on c's bed: XY box centre at the bed's centre, lowest
/// point at z = 0.
TriangleMesh placed(TriangleMesh m, const PrintConfig& c);

/// Axis-aligned box.
TriangleMesh box(const Vec3& min, const Vec3& max);

/// Icosphere of radius r about c, `levels` times subdivided (20·4^levels faces).
TriangleMesh icosphere(const Vec3& c, double r, int levels);

/// Splits every face into 4 (midpoint subdivision, no smoothing), `levels` times.
TriangleMesh subdivide(const TriangleMesh& m, int levels);

/// Appends b's vertices and faces to a.
void append(TriangleMesh& a, const TriangleMesh& b);

/// The analytic solids of the end-to-end issue (0.2 mm layers, max_angle 30°), with curved
/// tops the non-planar pipeline must follow within 0.02 mm (p95):
/// saddle: 24 × 24 mm, top 10 + (x² − y²) / 60 about its centre;
TriangleMesh saddle();
/// sine roof: 50 × 30 mm, top 8 + sin(2πx / 25); `nx` × `ny` grid quads;
TriangleMesh sine_roof(int nx = 150, int ny = 60);
/// two domed towers: a 3 mm plate 80 × 40 mm with two 20 × 20 mm towers whose tops are
/// 18 + 2 cos(0.1 dx) cos(0.1 dy) (one closed height field; its walls one 0.5 mm step wide);
TriangleMesh domed_towers();
/// dome cut by a box: the top of a sphere of radius 40 over a 24 × 24 mm square, 6 mm high
/// at the corners.
TriangleMesh dome_cut_by_box();
/// rib: a wing rib 80 × 12 mm whose top rises from 0.3 mm at its nose (x = 0) to 12.3 mm
/// and falls to 7.35 mm at its tail, 0.3 + 12 sin(πx / 100) (at most 20.7° steep). No stack
/// over a plane can follow it: its layer count would have to change 40-fold along it.
TriangleMesh rib();
/// rib beside a tower: the rib with a 4 × 4 × 14 mm tower 2 mm past its end, taller than it.
TriangleMesh rib_beside_tower();
/// rib against a tower: the rib with a 10 × 4 × 14 mm tower against its side (x 30-40).
TriangleMesh rib_against_tower();
/// hollow roof: 40 × 40 mm, top 6 + 2.5 sin(x / 7) cos(y / 9) (at most 21° steep), hollow
/// inside: walls and floor `wall` mm thick, its ceiling the top lowered by `wall`. No stack fits
/// (the part is not solid under its top); a shell must rest on the wall's top alone.
TriangleMesh hollow_roof(double wall);

/// two reliefs: 70 × 30 mm, two curved tops too tall for a stack over a plane, apart by a
/// 20 mm plate 2 mm thick: at x < 25 the top is 4 + 3 sin(2πx / 25) cos(y / 8), at x ≥ 45 it is
/// 10 + 3 cos(2π(x − 45) / 25) cos(y / 8). Each gets its own shell (the multi-shell path the
/// shared bunny takes, at a thousandth of its cost).
TriangleMesh two_reliefs();

/// rib and domed tower: a rib 60 × 12 mm, top 0.3 + 12 sin(πx / 100) (no stack fits it), and
/// 20 mm past its end a 30 × 30 mm tower, top 18 + 2 cos(0.1 dx) cos(0.1 dy) about its centre
/// (x 80–110, y −9–21): a stack for the tower, a shell for the rib, planar walls between.
TriangleMesh rib_and_domed_tower();

/// rib and small domed tower: the rib of rib() (x 0–80) and, 7.5 mm past its end, a 15 × 15 mm
/// tower, top 18 + 2 cos(0.1 dx) cos(0.1 dy) about (95, 6): a stack for the tower covers less
/// than half the curved top, so a shell over both is planned first; the tower stands above the
/// rib, so one slicer run cannot print it (another slicer prints the stack).
TriangleMesh rib_and_small_domed_tower();

/// The shapes #19 asks the quality figures for, beside the ones above (a hollow dome: the hollow
/// roofs; a tall relief on a low base: the two reliefs):
/// mouse shell: 44 × 26 mm, top 3 + 7 (1 − ((x − 4) / 26)²)(1 − (y / 18)²) about its centre
/// (x −22–22, y −13–13; at most 29° steep), hollow: walls and floor 1.2 mm, its ceiling the top
/// lowered by 1.2 mm, as a computer mouse's shell;
TriangleMesh mouse_shell();
/// top over a pocket: 40 × 30 mm, top 8 + 1.5 sin(x / 6) cos(y / 8) (at most 15° steep), over a
/// closed 20 × 14 × 3.5 mm pocket (x 10–30, y 8–22, z 1.5–5) under part of it;
TriangleMesh top_over_pocket();
/// tops one over another: a 40 × 30 mm block, top 5 + cos(x / 7) cos(y / 6), and a 10 × 20 mm
/// column beside it (x 40–50, y 5–25, 11 mm tall) under a shelf from z = 10, top
/// 13 + cos((x − 40) / 6) cos((y − 15) / 6), reaching 10 mm out over the block (x 30–50);
TriangleMesh tops_one_over_another();
/// filleted block: a CAD block 40 × 30 × 12 mm whose top edges and corners are rounded with
/// 5 mm fillets (a quarter circle from the walls' top at z = 7 to the flat top; a sphere at
/// each corner): its curved top is the fillets' band from 2° to 30°, 2.3 mm wide;
TriangleMesh filleted_block();
/// terrain tile: 50 × 50 mm, top 6 + 1.8 sin(x / 7 + 0.3) cos(y / 9 + 1.1)
/// + 0.8 sin(x / 3.7 + 2) sin(y / 4.3 + 0.5) + 0.3 cos(x / 2.1 + 1) sin(y / 1.9 + 2.2): hills
/// and hollows, mostly under 30° steep.
TriangleMesh terrain_tile();

/// The shared test models folder (../shared/models beside the repo); empty if absent.
std::filesystem::path shared_models();

/// A fresh temporary folder for one test.
std::filesystem::path temp_dir(const std::string& name);

}  // namespace nonplanar::test
