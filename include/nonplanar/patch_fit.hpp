// Stage layers, first step: a NURBS surface per patch of the analysis (nurbs fits plain
// samples; this takes them from a patch's triangles and measures the fit against them).
#pragma once

#include <vector>

#include "nonplanar/analysis.hpp"
#include "nonplanar/context.hpp"
#include "nonplanar/fit.hpp"

namespace nonplanar {

/// Data samples of a patch: its vertices plus area-weighted points on its triangles
/// (`density` per mm², deterministic).
std::vector<Vec3> sample_patch(const TriangleMesh& mesh, const Patch& patch, double density);

/// Vertical distance between a surface and the patch's triangles, sampled at `density`
/// points per mm² and at the vertices: RMS and max, mm.
struct FitError {
  double rms = 0, max = 0;
  std::size_t samples = 0;
};
FitError measure_fit_error(const HeightField& s, const TriangleMesh& mesh, const Patch& patch,
                           double density);

/// Fits every patch of `analysis` that needs non-planar layers, except those listed in
/// `skip`; *patch_ids gets the patch index of each fit (same order).
Expected<std::vector<SurfaceFit>> fit_patches(const TriangleMesh& mesh, const Analysis& analysis,
                                              const FitParams& params, const std::vector<int>& skip,
                                              std::vector<int>* patch_ids, const Context& ctx);

/// Fit one patch: samples, footprint and minimum span (the patch's median edge length) from
/// the mesh, then fit_height_field. rms_error / max_error of the result are re-measured
/// against the triangles with measure_fit_error.
Expected<SurfaceFit> fit_patch(const TriangleMesh& mesh, const Patch& patch,
                               const FitParams& params, const Context& ctx);

}  // namespace nonplanar
