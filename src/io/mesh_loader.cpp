#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/mesh_topology.hpp"
#include "io/mesh_buffer.hpp"
#include "io/readers.hpp"
#include "io/repair.hpp"
#include "nonplanar/io.hpp"

namespace nonplanar {

const char* format_name(MeshFormat f) {
  switch (f) {
    case MeshFormat::stl_binary:
      return "binary STL";
    case MeshFormat::stl_ascii:
      return "ASCII STL";
    case MeshFormat::obj:
      return "OBJ";
    case MeshFormat::off:
      return "OFF";
    case MeshFormat::threemf:
      return "3MF";
  }
  return "unknown";
}

namespace {

constexpr double kMaxCoordinate = 1e7;  // mm; beyond this, doubles lose the weld tolerance

std::string lower_extension(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

std::string format_mm(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g mm", v);
  return buf;
}

Error with_file(const std::filesystem::path& file, Error e) {
  e.message = file.string() + ": " + e.message;
  return e;
}

std::optional<Error> check_params(const LoadParams& p) {
  auto bad = [](const char* key, const char* why) {
    return Error{Status::invalid_argument, std::string(key) + ": " + why};
  };
  if (!std::isfinite(p.scale) || p.scale <= 0) return bad("scale", "must be a finite number > 0");
  if (!std::isfinite(p.rotate_x_deg) || !std::isfinite(p.rotate_y_deg) ||
      !std::isfinite(p.rotate_z_deg))
    return bad("rotate", "angles must be finite");
  if (!p.bed_center.allFinite()) return bad("bed_center", "must be finite");
  if (!std::isfinite(p.weld_tolerance_rel) || p.weld_tolerance_rel < 0 ||
      p.weld_tolerance_rel > 1e-2)
    return bad("weld_tolerance_rel", "must be in [0, 0.01]");
  return std::nullopt;
}

}  // namespace

Expected<LoadedMesh> load_mesh(const std::filesystem::path& file, const LoadParams& params,
                               const Context& ctx) {
  ctx.progress("load", 0);
  if (auto e = check_params(params)) return *e;
  const std::string ext = lower_extension(file);
  if (ext != ".stl" && ext != ".obj" && ext != ".off" && ext != ".3mf")
    return Error{Status::unsupported, file.string() + ": unknown mesh format '" + ext +
                                          "' (use .stl, .obj, .off or .3mf)"};
  // 50 bytes per binary STL triangle bounds any reasonable file for max_triangles.
  auto bytes = io::read_file_bytes(file, 64 + params.max_triangles * 200);
  if (!bytes) return with_file(file, bytes.error());
  ctx.progress("load", 0.1);

  LoadedMesh out;
  Expected<TriangleMesh> raw = Error{};
  const std::string_view data = bytes->view();
  if (ext == ".stl") {
    raw = io::parse_stl(data, &out.format);
  } else if (ext == ".obj") {
    out.format = MeshFormat::obj;
    raw = io::parse_obj(data);
  } else if (ext == ".off") {
    out.format = MeshFormat::off;
    raw = io::parse_off(data);
  } else {
    out.format = MeshFormat::threemf;
    raw = io::parse_3mf(data, params.max_triangles, &out.objects);
    if (!out.objects.several()) out.objects = {};
  }
  *bytes = io::FileBytes();  // unmap
  if (!raw) return with_file(file, raw.error());
  if (raw->faces.empty()) return with_file(file, {Status::invalid_mesh, "mesh has no triangles"});
  if (raw->faces.size() > params.max_triangles)
    return with_file(file, {Status::invalid_mesh, std::to_string(raw->faces.size()) +
                                                      " triangles, over the limit of " +
                                                      std::to_string(params.max_triangles)});
  if (auto e = io::check_face_indices(*raw)) return with_file(file, *e);
  for (const Vec3& v : raw->vertices)
    if (v.cwiseAbs().maxCoeff() > kMaxCoordinate)
      return with_file(file, {Status::invalid_mesh, "a coordinate exceeds 1e7 in magnitude"});
  if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
  ctx.progress("load", 0.4);

  out.input_triangles = raw->faces.size();
  out.weld_tolerance = io::weld_tolerance(*raw, params.weld_tolerance_rel);
  out.mesh = io::weld(std::move(*raw), out.weld_tolerance, &out.defects.collapsed_faces,
                      &out.objects.face);
  raw = Error{};
  out.defects.duplicate_faces = io::remove_duplicate_faces(out.mesh, &out.objects.face);
  if (out.mesh.faces.empty())
    return with_file(file, {Status::invalid_mesh, "every triangle is degenerate"});
  out.weld_tolerance *= params.scale;
  io::transform_and_place(out.mesh, params);
  ctx.progress("load", 0.7);

  const MeshTopology topo = build_topology(out.mesh);
  out.defects.open_edges = topo.open_edges;
  out.defects.non_manifold_edges = topo.non_manifold_edges;
  out.defects.inconsistent_edges = topo.inconsistent_edges;
  out.defects.zero_area_faces = io::count_zero_area_faces(out.mesh, out.weld_tolerance);
  int shells = 0;
  face_components(out.mesh, &shells);
  out.defects.shells = static_cast<std::size_t>(shells);
  out.defects.faces_flipped = io::orient_outward(out.mesh, topo, &out.defects.was_inverted);

  const MeshDefects& d = out.defects;
  if (d.open_edges)
    out.warnings.push_back(std::to_string(d.open_edges) + " open edges (mesh has holes)");
  if (d.non_manifold_edges)
    out.warnings.push_back(std::to_string(d.non_manifold_edges) + " non-manifold edges");
  if (d.inconsistent_edges)
    out.warnings.push_back(std::to_string(d.inconsistent_edges) +
                           " edges with inconsistent winding (faces reoriented)");
  if (d.was_inverted) out.warnings.push_back("mesh was inside out (normals flipped)");
  if (d.zero_area_faces)
    out.warnings.push_back(std::to_string(d.zero_area_faces) + " zero-area faces");
  if (d.duplicate_faces)
    out.warnings.push_back(std::to_string(d.duplicate_faces) +
                           " duplicate faces removed (copies of another face)");
  if (d.collapsed_faces)
    out.warnings.push_back(std::to_string(d.collapsed_faces) + " of " +
                           std::to_string(out.input_triangles) +
                           " faces were degenerate and removed by welding (tolerance " +
                           format_mm(out.weld_tolerance) + ")");
  ctx.progress("load", 1.0);
  return out;
}

}  // namespace nonplanar
