// Analytic test solids built in memory: height-field blocks, boxes, spheres. Every solid is
// closed and outward-oriented, so tests know its exact top surface and volume.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

#include "nonplanar/mesh.hpp"

namespace nonplanar::test {

/// Closed block over [x0,x1]×[y0,y1]: top z = f(x, y) on an nx × ny grid of quads, flat
/// bottom at z = base, vertical walls. Requires f > base.
TriangleMesh height_field_solid(const std::function<double(double, double)>& f, double x0,
                                double x1, double y0, double y1, int nx, int ny, double base = 0.0);

/// Axis-aligned box.
TriangleMesh box(const Vec3& min, const Vec3& max);

/// Icosphere of radius r about c, `levels` times subdivided (20·4^levels faces).
TriangleMesh icosphere(const Vec3& c, double r, int levels);

/// Splits every face into 4 (midpoint subdivision, no smoothing), `levels` times.
TriangleMesh subdivide(const TriangleMesh& m, int levels);

/// Appends b's vertices and faces to a.
void append(TriangleMesh& a, const TriangleMesh& b);

/// The shared test models folder (../shared/models beside the repo); empty if absent.
std::filesystem::path shared_models();

/// A fresh temporary folder for one test.
std::filesystem::path temp_dir(const std::string& name);

}  // namespace nonplanar::test
