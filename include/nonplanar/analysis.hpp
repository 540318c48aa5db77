// Stage analysis (paper §2): facet selection, discrete curvature, creases and patches.
//
// Notation: n_f face normal (unit), θ_f = angle(n_f, +Z); K(v) angle deficit at vertex v
// (2π − Σ corner angles inside the surface, π − Σ on its boundary); K̂(v) = K(v) / A(v) with
// A(v) one third of the area of the faces around v (the barycentric area), in 1/mm².
#pragma once

#include <cstddef>
#include <vector>

#include "nonplanar/context.hpp"
#include "nonplanar/mesh.hpp"
#include "nonplanar/status.hpp"

namespace nonplanar {

/// Inputs of analyze(). Degrees and millimetres.
struct AnalysisParams {
  double max_angle_deg = 30.0;  ///< a face is printable non-planar when θ_f < max_angle
  /// Vertex discontinuous when K̂(v) > tau (1/mm²): sharper than a sphere of radius
  /// 1/√tau ≈ 3 mm, which a fitted surface would round off visibly.
  double tau = 0.1;
  double epsilon = 0.1;            ///< ... or |K̂(v) − K̂(w)| > epsilon for a neighbour w
  double crease_angle_deg = 20.0;  ///< dihedral angle between painted faces that cuts a patch
  double min_layer_height = 0.1;   ///< a patch flatter than this needs no non-planar layers
  double min_patch_area = 4.0;     ///< mm²; smaller patches are dropped
};

/// Why a patch does or does not need non-planar layers.
enum class PatchVerdict { nonplanar, flat, too_small };
const char* verdict_name(PatchVerdict v);

/// A connected set of painted faces with no discontinuity or crease inside.
struct Patch {
  std::vector<int> faces;  ///< face indices into the analysed mesh
  double area = 0.0;       ///< mm²
  Vec2 xy_min{0, 0}, xy_max{0, 0};
  double z_min = 0.0, z_max = 0.0;
  double max_slope_deg = 0.0;  ///< steepest face θ_f in the patch
  PatchVerdict verdict = PatchVerdict::flat;
  bool needs_nonplanar() const { return verdict == PatchVerdict::nonplanar; }
};

/// Output of analyze().
struct Analysis {
  std::vector<char> painted;        ///< F flags: θ_f < max_angle
  std::vector<double> curvature;    ///< V values of K̂ on the painted surface (0 off it)
  std::vector<char> discontinuous;  ///< F flags: painted face touching a discontinuous vertex
  std::size_t painted_faces = 0;
  std::size_t discontinuous_faces = 0;
  std::size_t crease_edges = 0;  ///< painted–painted edges sharper than crease_angle
  std::vector<Patch> patches;    ///< sorted by decreasing area
  std::vector<int> face_patch;   ///< F entries: patch index or −1
};

/// Run facet selection, curvature, discontinuity and crease detection and patch extraction
/// on a welded, outward-oriented mesh. Errors: invalid_argument naming the parameter,
/// cancelled.
Expected<Analysis> analyze(const TriangleMesh& mesh, const AnalysisParams& params,
                           const Context& ctx);

}  // namespace nonplanar
